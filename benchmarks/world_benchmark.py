"""
How close the MuJoCo world node runs to MuJoCo's own limits, measured in one run.

Every figure is printed next to the limit it is compared with, and the whole report is written
as JSON (output/benchmark.json unless --json says otherwise). What runs where:

- service round trips and the spawn cost as the world grows: the world node in this process,
  on an executor thread of its own shared with a trivial std_srvs/Trigger service, called from
  a client node on a second executor thread (the layout of test/conftest.py);
- free-running speed, real-time factor, start-up and turning accuracy: the installed
  mujoco_world console script (and robot_turning_server) as separate processes, as users run
  them, observed from this process;
- raw physics and core operations: service_tutorial.sim.world.World in this process, no ROS;
- the camera's cost: mujoco_world as a process, streaming to a subscriber here;
- the sensors' cost: a scan and a robot camera frame in a World in this process against bare
  MuJoCo calls, and mujoco_world as a process with and without a subscriber to a laser;
- answers that need no simulation: model_services without a world, and robot_turning_server
  in this process;
- the standard simulation interfaces (SpawnEntities, StepSimulation, GetEntitiesStates,
  LoadWorld): the world node in this process, paused, against MuJoCo's own batch, bare mj_step
  and the World;
- the web page's cost: mujoco_world as a process with web:=false and web:=true, and with one
  headless Chromium on its page;
- gz-sim's lidar and depth camera in a World in this process against bare MuJoCo calls, and
  three Burgers started with world:= and create, beside Gazebo Harmonic's published figures.

Run it with scripts/benchmark [--quick] [--json PATH].
"""

import argparse
from dataclasses import dataclass
import os
import sys
import tempfile
import time

from answers import answers_table
from camera import camera_table
from core import core_table
from gz_sim import burger_world_table, gz_sensor_table
from harness import BenchmarkError, Observer
from lesson_services import lesson_services_table
from report import machine, targets, write_json
from round_trips import round_trip_table
from sensors import sensor_table
from service_tutorial.testing.isolation import isolate_ros_graph
from spawn_cost import sdf_spawn_table, spawn_cost_table
from spawn_growth import growth_table
from speed import speed_tables
from standard_interfaces import standard_table
from startup import startup_table
from turning import turning_tables
from web_page import web_table
from world_loading import worlds_table

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_JSON = os.path.join(ROOT, 'output', 'benchmark.json')


@dataclass
class Config:
    """Counts and durations of one benchmark run."""

    calls: int = 200                       # round trips per service
    growth_counts: tuple = (1, 10, 50)     # models present for the spawn-cost rows
    growth_calls: int = 40                 # spawns per world size
    lesson_calls: int = 40                 # R2-D2 spawns against MuJoCo's path, warm and cold
    robot_counts: tuple = (1, 10, 50)      # tinybots for speed and real-time rows
    speed_window: float = 2.0              # wall s per free-running measurement window
    speed_rounds: int = 3                  # alternating raw / world node windows
    speed_settle: float = 0.3              # wall s of driving after unpausing, before a window
    real_time_window: float = 3.0          # wall s per real-time measurement window
    warm_up: float = 1.0                   # wall s of driving before a window starts
    startup_runs: int = 5
    durations: tuple = (1, 2, 5)           # s, turning grid
    velocities: tuple = (0.1, 0.5, 1.0, 1.5)  # rad/s, turning grid
    turning_rtf: float = 2.0               # real_time_factor of the turning grid's world
    turning_check_rtfs: tuple = (1.0, 2.0, 5.0, 0.0)  # real_time_factor check of one turn
    turning_check_point: tuple = (2, 1.0)  # (s, rad/s) of that check
    core_spawns: int = 5                   # R2-D2s spawned into a World in this process
    cost_counts: tuple = (1, 50)           # tinybots present for the spawn-cost rows
    cost_calls: int = 60                   # spawn/delete cycles per spawn-cost row
    box_count: int = 200                   # boxes spawned, then deleted, in the box row
    step_rounds: int = 5                   # World.step against bare mj_step, best of
    step_count: int = 1000                 # steps per round
    camera_window: float = 2.0             # wall s of streaming camera measured
    scan_repeats: int = 900                # scans of each kind in the laser rows
    camera_frames: int = 20                # frames per timing of the robot camera row
    standard_batch: int = 50               # tinybots of a SpawnEntities batch and its states
    standard_rounds: int = 5               # alternating rounds of the batch rows
    standard_step_rounds: int = 9          # alternating rounds of the stepping row, best of
    standard_steps: int = 10_000           # steps of one StepSimulation call
    standard_step_robots: int = 10         # driving tinybots stepped
    standard_calls: int = 100              # GetEntitiesStates round trips
    web_rounds: int = 5                    # windows per case of the web page's rows
    web_window: float = 3.0                # wall s per window of the web page's rows
    web_robots: int = 50                   # tinybots of the row with a browser
    log_path: str = os.path.join(tempfile.gettempdir(), 'world_benchmark-nodes.log')


QUICK = Config(calls=5, growth_counts=(1, 2), growth_calls=3, lesson_calls=2,
               robot_counts=(1,),
               speed_window=0.3, speed_rounds=1, speed_settle=0.1, real_time_window=0.3,
               warm_up=0.2, startup_runs=1,
               durations=(1,), velocities=(0.5,), turning_rtf=4.0, turning_check_rtfs=(),
               core_spawns=3, cost_counts=(1, 2), cost_calls=3, box_count=5, step_rounds=2,
               step_count=200, camera_window=0.3, scan_repeats=20, camera_frames=2,
               standard_batch=3, standard_rounds=1, standard_step_rounds=2, standard_steps=200,
               standard_step_robots=2, standard_calls=3, web_rounds=1, web_window=0.3,
               web_robots=2)


SECTIONS = ('round_trips', 'spawn_growth', 'speed', 'startup', 'turning', 'core', 'spawn_cost',
            'camera', 'sensors', 'answers', 'standard', 'web', 'gz')


def run(config, *, sections=SECTIONS, report=print):
    """Measure the selected sections; rclpy must be initialised. Return the tables."""
    observer = Observer()
    tables = []

    def add(*new_tables):
        for table in new_tables:
            tables.append(table)
            report(table.render() + '\n')
    # In the order they run. Start-up first: once this process's DDS participant has made and
    # dropped the thousands of topics of the in-process sections, its new service clients take
    # a second longer to match a new world (1.9 s against 0.85 s), whatever the world does.
    measurements = {
        'startup': lambda: [startup_table(observer, config)],
        'gz': lambda: [gz_sensor_table(config), burger_world_table(observer, config)],
        'round_trips': lambda: [round_trip_table(observer, config),
                                lesson_services_table(observer, config)],
        'spawn_growth': lambda: [growth_table(observer, config)],
        'speed': lambda: speed_tables(observer, config),
        'turning': lambda: turning_tables(observer, config),
        'core': lambda: [core_table(config)],
        'spawn_cost': lambda: [spawn_cost_table(config), sdf_spawn_table(config)],
        'camera': lambda: [camera_table(observer, config)],
        'sensors': lambda: [sensor_table(observer, config)],
        'answers': lambda: [answers_table(observer, config)],
        'standard': lambda: [standard_table(observer, config), worlds_table(observer, config)],
        'web': lambda: [web_table(observer, config)],
    }
    try:
        for section, measure in measurements.items():
            if section in sections:
                add(*measure())
    finally:
        observer.close()
    add(targets(tables))
    return tables


def parse_args(argv):
    """Read the command line."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--quick', action='store_true',
                        help='tiny counts and windows: checks that everything runs')
    parser.add_argument('--json', default=DEFAULT_JSON, metavar='PATH',
                        help=f'where to write the report (default {DEFAULT_JSON})')
    parser.add_argument('--sections', default=','.join(SECTIONS),
                        help=f'comma-separated subset of {",".join(SECTIONS)}')
    parser.add_argument('--calls', type=int, help='round trips per service (default 200)')
    parser.add_argument('--robots', help='robot counts for speed rows, e.g. 1,10,50')
    parser.add_argument('--turning-rtf', type=float,
                        help='real_time_factor of the turning grid (default 2)')
    args = parser.parse_args(argv)
    sections = tuple(s.strip() for s in args.sections.split(',') if s.strip())
    unknown = sorted(set(sections) - set(SECTIONS))
    if unknown:
        parser.error(f'unknown section(s) {", ".join(unknown)}; choose from '
                     f'{", ".join(SECTIONS)}')
    config = Config(**QUICK.__dict__) if args.quick else Config()
    if args.calls is not None:
        config.calls = args.calls
    if args.robots:
        config.robot_counts = tuple(int(v) for v in args.robots.split(','))
    if args.turning_rtf is not None:
        config.turning_rtf = args.turning_rtf
    return config, sections, args.json


def main(argv=None):
    """Run the benchmark on a ROS domain of its own and print and save the report."""
    config, sections, json_path = parse_args(sys.argv[1:] if argv is None else argv)
    isolate_ros_graph()
    import rclpy
    rclpy.init()
    try:
        info = machine()
        print(f"machine: {info['nproc']} x {info['cpu']}, Python {info['python']}, MuJoCo "
              f"{info['mujoco']}, {info['rmw']}, load {info['load_average_at_start']}\n")
        start = time.monotonic()
        tables = run(config, sections=sections)
        write_json(json_path, tables, config, info)
        print(f'took {time.monotonic() - start:.0f} s; written to {json_path}; the in-process '
              f'nodes logged to {config.log_path}')
    except BenchmarkError as error:
        print(f'benchmark failed: {error}', file=sys.stderr)
        return 1
    finally:
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
