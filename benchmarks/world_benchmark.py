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
  in this process.

Run it with scripts/benchmark [--quick] [--json PATH].
"""

import argparse
import contextlib
import ctypes
from dataclasses import dataclass, field
import datetime
import json
import math
import os
import platform
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

import mujoco
import numpy as np
import spawn_cost
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The tests' way of keeping a run's ROS graph to itself (test/ is not a package).
sys.path.insert(0, os.path.join(ROOT, 'test'))
from ros_isolation import isolate_ros_graph  # noqa: E402, I100
DEFAULT_JSON = os.path.join(ROOT, 'output', 'benchmark.json')
PACKAGE = 'service_tutorial'
WORLD_SERVICES = ('spawn_urdf_model', 'delete_model', 'reset_simulation', 'reset_world',
                  'pause_physics', 'unpause_physics', 'get_model_list', 'get_model_state',
                  'set_model_state')
# Fleet layout: ten robots to a row, far enough apart that their circles never touch.
SPACING = 1.5
# What every robot of a fleet is told on cmd_vel: circles of 0.4 m radius.
DRIVE_LINEAR_X = 0.2
DRIVE_ANGULAR_Z = 0.5
# R2-D2 where the lesson spawns it: (-2, 1, 1), turned -90 degrees about z.
LESSON_POSITION = (-2.0, 1.0, 1.0)
LESSON_ORIENTATION = (math.sqrt(0.5), 0.0, 0.0, -math.sqrt(0.5))  # (w, x, y, z)
# After a turn, how long (simulated s) the robot is given to come to rest before measuring.
SETTLE_TIME = 0.5
TURNING_TARGET_PERCENT = 2.0
PR_SET_PDEATHSIG = 1  # prctl option, from linux/prctl.h


class BenchmarkError(RuntimeError):
    """A measurement could not be taken; the message says which and why."""


# The fleet the real-time CPU target is set for. Smaller fleets print the same comparison, but
# there the world's fixed costs (/clock at 250 Hz, a tick every 20 ms) outweigh the physics.
CPU_TARGET_ROBOTS = 50
CPU_LIMIT_RATIO = 2.0


@dataclass
class Config:
    """Counts and durations of one benchmark run."""

    calls: int = 200                       # round trips per service
    growth_counts: tuple = (1, 10, 50)     # models present for the spawn-cost rows
    growth_calls: int = 40                 # spawns per world size
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
    cost_calls: int = 20                   # spawn/delete cycles per spawn-cost row
    box_count: int = 200                   # boxes spawned, then deleted, in the box row
    step_rounds: int = 5                   # World.step against bare mj_step, best of
    step_count: int = 1000                 # steps per round
    camera_window: float = 2.0             # wall s of streaming camera measured
    scan_repeats: int = 300                # scans per timing of the laser rows
    camera_frames: int = 20                # frames per timing of the robot camera row
    log_path: str = os.path.join(tempfile.gettempdir(), 'world_benchmark-nodes.log')


QUICK = Config(calls=5, growth_counts=(1, 2), growth_calls=3, robot_counts=(1,),
               speed_window=0.3, speed_rounds=1, speed_settle=0.1, real_time_window=0.3,
               warm_up=0.2, startup_runs=1,
               durations=(1,), velocities=(0.5,), turning_rtf=4.0, turning_check_rtfs=(),
               core_spawns=3, cost_counts=(1, 2), cost_calls=3, box_count=5, step_rounds=2,
               step_count=200, camera_window=0.3, scan_repeats=20, camera_frames=2)


@dataclass
class Table:
    """One section of the report: named columns, rows of values, and what they mean."""

    key: str
    title: str
    columns: list            # (heading, format) pairs; format '' leaves the value as text
    rows: list = field(default_factory=list)
    note: str = ''

    def as_dict(self):
        """Return the table as plain data for JSON."""
        return {'title': self.title, 'columns': [heading for heading, _ in self.columns],
                'rows': self.rows, 'note': self.note}

    def render(self):
        """Return the table as aligned text."""
        headings = [heading for heading, _ in self.columns]
        cells = [[_format(value, fmt) for value, (_, fmt) in zip(row, self.columns)]
                 for row in self.rows]
        widths = [max([len(h)] + [len(row[i]) for row in cells]) for i, h in enumerate(headings)]
        lines = [self.title, '  '.join(h.rjust(w) for h, w in zip(headings, widths)),
                 '  '.join('-' * w for w in widths)]
        lines += ['  '.join(c.rjust(w) for c, w in zip(row, widths)) for row in cells]
        if self.note:
            lines.append(self.note)
        return '\n'.join(lines)


def _format(value, fmt):
    if isinstance(value, bool):
        return 'yes' if value else 'NO'
    if fmt and isinstance(value, (int, float)):
        return format(value, fmt)
    return str(value)


def percentiles(samples):
    """Return p50, p95 and p99 of samples in seconds, in milliseconds."""
    if not samples:
        raise BenchmarkError('no samples to take percentiles of')
    return [float(v) * 1e3 for v in np.percentile(samples, [50, 95, 99])]


def median_ms(samples):
    """Return the median of samples in seconds, in milliseconds."""
    return float(statistics.median(samples)) * 1e3


def machine():
    """Describe the machine and software the figures come from."""
    cpu = 'unknown'
    try:
        with open('/proc/cpuinfo') as cpuinfo:
            for line in cpuinfo:
                if line.startswith('model name'):
                    cpu = line.split(':', 1)[1].strip()
                    break
    except OSError:
        pass
    import rclpy.utilities
    return {
        'nproc': os.cpu_count(),
        'cpu': cpu,
        'python': platform.python_version(),
        'mujoco': mujoco.__version__,
        'rmw': rclpy.utilities.get_rmw_implementation_identifier(),
        'load_average_at_start': [round(v, 2) for v in os.getloadavg()],
        'date': datetime.datetime.now().isoformat(timespec='seconds'),
    }


# --------------------------------------------------------------------------------- models


def model_path(name):
    """Return the installed URDF file of one of the package's models."""
    from ament_index_python.packages import get_package_share_directory
    return os.path.join(get_package_share_directory(PACKAGE), 'models', name + '.urdf')


def read_model(name):
    """Return the URDF text of one of the package's models."""
    with open(model_path(name)) as model_file:
        return model_file.read()


def fleet_names(count):
    """Return the model names (and namespaces) of a fleet of tinybots."""
    return [f'bot{index}' for index in range(count)]


def fleet_position(index):
    """Return where the index-th tinybot of a fleet stands."""
    return (SPACING * (index % 10), SPACING * (index // 10), 0.0)


def fleet_parameters(count, real_time_factor):
    """Return world node parameters that start it with a fleet of tinybots."""
    poses = []
    for index in range(count):
        poses.extend(fleet_position(index)[:2] + (0.0, 0.0))
    names = fleet_names(count)
    return {
        'real_time_factor': float(real_time_factor),
        'models': ['tinybot.urdf'] * count,
        'model_names': names,
        'model_namespaces': list(names),
        'model_poses': [float(v) for v in poses],
        # The robots drive for the whole measurement on one command; a sim-time timeout
        # would stop them between two commands sent at wall-clock pace.
        'cmd_vel_timeout': 0.0,
        # The fleet's grid reaches beyond the yard's walls; the raw fleet has no scenery.
        'scenery': '',
    }


def core_fleet(count, *, driving):
    """Return a ROS-free World holding the same fleet, driving like the node's fleet."""
    from service_tutorial.sim.world import World
    world = World(cmd_vel_timeout=0.0)
    path = model_path('tinybot')
    for index, name in enumerate(fleet_names(count)):
        world.spawn_urdf_file(name, path, position=fleet_position(index))
        if driving:
            world.command_velocity(name, DRIVE_LINEAR_X, DRIVE_ANGULAR_Z)
    return world


# ------------------------------------------------------------------------- ROS plumbing


class Observer:
    """A client node on an executor thread of its own: calls services, counts messages."""

    def __init__(self):
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        self.node = Node('world_benchmark')
        self._executor = SingleThreadedExecutor()
        self._executor.add_node(self.node)
        self._thread = threading.Thread(target=self._executor.spin, daemon=True)
        self._thread.start()
        self._clients = {}

    def client(self, srv_type, name):
        """Return a client of a service, made once and kept."""
        key = (srv_type, name)
        if key not in self._clients:
            self._clients[key] = self.node.create_client(srv_type, name)
        return self._clients[key]

    def wait_for_service(self, srv_type, name, *, timeout=30.0, process=None):
        """Wait until a service has a server; rclpy's own wait polls only every 0.25 s."""
        client = self.client(srv_type, name)
        deadline = time.monotonic() + timeout
        while not client.service_is_ready():
            if process is not None:
                process.check()
            if time.monotonic() > deadline:
                raise BenchmarkError(f'service {name} did not appear within {timeout} s')
            time.sleep(0.002)

    def call(self, srv_type, name, request, *, timeout=30.0):
        """Call a service and return its response, waiting on the future without polling."""
        done = threading.Event()
        future = self.client(srv_type, name).call_async(request)
        future.add_done_callback(lambda _: done.set())
        if not done.wait(timeout):
            raise BenchmarkError(f'service {name} did not answer within {timeout} s')
        return future.result()

    def call_async(self, srv_type, name, request):
        """Start a service call; return its future."""
        return self.client(srv_type, name).call_async(request)

    def timed_calls(self, srv_type, name, make_request, count, *, check=None):
        """Call a service count times; return the round-trip times in seconds."""
        samples = []
        for index in range(count):
            request = make_request(index)
            start = time.perf_counter()
            response = self.call(srv_type, name, request)
            samples.append(time.perf_counter() - start)
            if check is not None and not check(response):
                raise BenchmarkError(f'{name} failed: {response}')
        return samples

    def counter(self, msg_type, topic):
        """Count the messages arriving on a topic; return the counter and its subscription."""
        counter = [0]

        def count(_):
            counter[0] += 1
        subscription = self.node.create_subscription(msg_type, topic, count, 10)
        return counter, subscription

    def close(self):
        """Stop the executor thread and destroy the node."""
        self._executor.shutdown(timeout_sec=5.0)
        self._thread.join(timeout=5.0)
        self.node.destroy_node()


def _die_with_parent():
    """In a child process: ask Linux for SIGTERM when the benchmark dies without stopping it."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except (OSError, AttributeError):
        pass


class NodeProcess:
    """One of the package's executables run as users run it, stopped with SIGINT."""

    def __init__(self, executable, *, node_name=None, parameters=None, ros_args=(),
                 log_dir=None):
        path = shutil.which(executable)
        if path is None:
            raise BenchmarkError(f'executable {executable!r} is not on PATH: run '
                                 'scripts/setup and source scripts/env.sh')
        self.executable = executable
        self._log_dir = log_dir or tempfile.mkdtemp(prefix='world_benchmark-')
        args = [path]
        if parameters or ros_args:
            args.append('--ros-args')
        if parameters:
            params_path = os.path.join(self._log_dir, f'{executable}.yaml')
            with open(params_path, 'w') as params_file:
                yaml.safe_dump({node_name: {'ros__parameters': parameters}}, params_file)
            args += ['--params-file', params_path]
        args += list(ros_args)
        self.log_path = os.path.join(self._log_dir, f'{executable}.log')
        self._log = open(self.log_path, 'w')
        self.process = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT,
                                        cwd=self._log_dir, preexec_fn=_die_with_parent)

    def check(self):
        """Raise BenchmarkError with the end of its log if the process has exited."""
        if self.process.poll() is not None:
            raise BenchmarkError(f'{self.executable} exited with status '
                                 f'{self.process.returncode}:\n{self.log_tail()}')

    def log_tail(self, lines=20):
        """Return the last lines the process printed."""
        self._log.flush()
        with open(self.log_path) as log_file:
            return ''.join(log_file.readlines()[-lines:])

    def stop(self):
        """Stop the process with Ctrl-C, or kill it if it does not go within 10 s."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.stop()


def sim_time_sample(observer, model_name, *, timeout=30.0):
    """Return (simulation time, wall time) from one get_model_state round trip."""
    from service_tutorial.conversions import seconds_of
    from srv_interfaces.srv import GetModelState
    start = time.monotonic()
    response = observer.call(GetModelState, '/mujoco/get_model_state',
                             GetModelState.Request(model_name=model_name), timeout=timeout)
    end = time.monotonic()
    if not response.success:
        raise BenchmarkError(f'get_model_state {model_name}: {response.status_message}')
    return seconds_of(response.header.stamp), 0.5 * (start + end), response


def wait_for_world(observer, process, model_name, *, tries=6):
    """
    Wait until the world process answers get_model_state for model_name.

    A service can be ready before its server has matched the client's response reader; a
    response sent in that gap is lost (a known DDS race), so a first call that gets no answer
    within 5 s is made again.
    """
    from srv_interfaces.srv import GetModelState
    observer.wait_for_service(GetModelState, '/mujoco/get_model_state', process=process)
    for attempt in range(tries):
        try:
            return sim_time_sample(observer, model_name, timeout=5.0)
        except BenchmarkError:
            process.check()
            if attempt == tries - 1:
                raise


def wait_until_gone(observer, srv_type, name, *, timeout=10.0):
    """Wait until no server offers a service any more (a stopped world left the graph)."""
    client = observer.client(srv_type, name)
    deadline = time.monotonic() + timeout
    while client.service_is_ready() and time.monotonic() < deadline:
        time.sleep(0.01)


class Fleet:
    """cmd_vel publishers to every robot of a fleet in a running world."""

    def __init__(self, observer, count):
        from geometry_msgs.msg import Twist
        self._observer = observer
        self.names = fleet_names(count)
        self.publishers = [observer.node.create_publisher(Twist, f'/{name}/cmd_vel', 10)
                           for name in self.names]
        self.command = Twist()
        self.command.linear.x = DRIVE_LINEAR_X
        self.command.angular.z = DRIVE_ANGULAR_Z

    def start(self, process, *, timeout=30.0):
        """Wait for every robot's cmd_vel subscription, command it, and see bot0 turn."""
        deadline = time.monotonic() + timeout
        while any(p.get_subscription_count() == 0 for p in self.publishers):
            process.check()
            if time.monotonic() > deadline:
                raise BenchmarkError('the world did not subscribe to every cmd_vel')
            time.sleep(0.01)
        self.publish()
        while True:
            _, _, state = sim_time_sample(self._observer, self.names[0])
            if state.twist.angular.z > 0.8 * DRIVE_ANGULAR_Z:
                return
            if time.monotonic() > deadline:
                raise BenchmarkError(f'{self.names[0]} did not start turning on cmd_vel')
            self.publish()
            time.sleep(0.02)

    def publish(self):
        """Send the driving command to every robot."""
        for publisher in self.publishers:
            publisher.publish(self.command)

    def drive_for(self, seconds):
        """Keep commanding the fleet (twice a second) for seconds of wall time."""
        end = time.monotonic() + seconds
        while True:
            remaining = end - time.monotonic()
            if remaining <= 0.0:
                return
            time.sleep(min(0.5, remaining))
            self.publish()

    def destroy(self):
        """Remove the publishers."""
        for publisher in self.publishers:
            self._observer.node.destroy_publisher(publisher)


# ---------------------------------------------------------------------- round trips


class TrivialService:
    """A node whose std_srvs/Trigger service does nothing: the floor of any round trip."""

    def __init__(self):
        from rclpy.node import Node
        from std_srvs.srv import Trigger
        self.node = Node('benchmark_trivial')
        self.trigger_srv = self.node.create_service(Trigger, '~/trigger', self.trigger_callback)

    @staticmethod
    def trigger_callback(request, response):
        """Answer at once."""
        response.success = True
        return response


def spawn_request(index):
    """Return a request that spawns R2-D2 where the lesson does."""
    from geometry_msgs.msg import Pose
    from service_tutorial.conversions import fill_pose_msg
    from srv_interfaces.srv import SpawnModel
    pose = fill_pose_msg(Pose(), LESSON_POSITION, LESSON_ORIENTATION)
    return SpawnModel.Request(model_name='r2d2', model_xml=read_model('r2d2'),
                              initial_pose=pose, reference_frame='world')


def core_round_trips(models_present, calls, *, with_reset=True):
    """Time spawn, delete and reset_world of R2-D2 done directly on a ROS-free World."""
    world = core_fleet(models_present, driving=False)
    urdf = read_model('r2d2')
    spawns, deletes, resets = [], [], []
    for _ in range(calls):
        start = time.perf_counter()
        world.spawn_urdf('r2d2', urdf, position=LESSON_POSITION,
                         orientation=LESSON_ORIENTATION)
        middle = time.perf_counter()
        world.delete_model('r2d2')
        spawns.append(middle - start)
        deletes.append(time.perf_counter() - middle)
    if with_reset:
        world.spawn_urdf('r2d2', urdf, position=LESSON_POSITION, orientation=LESSON_ORIENTATION)
        for _ in range(calls):
            start = time.perf_counter()
            world.reset_world()
            resets.append(time.perf_counter() - start)
    return {'spawn': spawns, 'delete': deletes, 'reset_world': resets}


def node_round_trips(observer, models_present, calls, *, with_reset=True, core=None):
    """
    Time the world node's services from a client in this process.

    The world node runs in real time (its default) with models_present tinybots, on one
    executor thread together with a trivial Trigger service. It logs at its default level; the
    console lines go to a file (see quiet_console).

    Each round times a spawn, a delete and a Trigger call. With core (a ROS-free World holding
    the same models), it first times the same spawn and delete on core: the figures that are
    compared then see the same load on a shared machine. The node's world is paused while the
    core works, so that its ticks do not take turns with the core on the interpreter.
    """
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter
    from service_tutorial.world_node.node import MujocoWorld
    from srv_interfaces.srv import DeleteModel, SpawnModel
    from std_srvs.srv import Empty, Trigger

    overrides = [Parameter(name, value=value)
                 for name, value in fleet_parameters(models_present, 1.0).items()]
    world = MujocoWorld(parameter_overrides=overrides)
    trivial = TrivialService()
    executor = SingleThreadedExecutor()
    executor.add_node(world)
    executor.add_node(trivial.node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    urdf = read_model('r2d2')
    try:
        for srv_type, name in ((SpawnModel, '/mujoco/spawn_urdf_model'),
                               (DeleteModel, '/mujoco/delete_model'),
                               (Empty, '/mujoco/reset_world'),
                               (Empty, '/mujoco/pause_physics'),
                               (Empty, '/mujoco/unpause_physics'),
                               (Trigger, '/benchmark_trivial/trigger')):
            observer.wait_for_service(srv_type, name)
        result = {'spawn': [], 'delete': [], 'core spawn': [], 'core delete': [],
                  'trigger': []}
        for index in range(calls + 3):  # the first three warm up
            samples = {}
            if core is not None:
                observer.call(Empty, '/mujoco/pause_physics', Empty.Request())
                start = time.perf_counter()
                core.spawn_urdf('r2d2', urdf, position=LESSON_POSITION,
                                orientation=LESSON_ORIENTATION)
                middle = time.perf_counter()
                core.delete_model('r2d2')
                samples['core spawn'] = [middle - start]
                samples['core delete'] = [time.perf_counter() - middle]
                observer.call(Empty, '/mujoco/unpause_physics', Empty.Request())
            samples['spawn'] = observer.timed_calls(
                SpawnModel, '/mujoco/spawn_urdf_model', spawn_request, 1,
                check=lambda r: r.success)
            samples['delete'] = observer.timed_calls(
                DeleteModel, '/mujoco/delete_model',
                lambda _: DeleteModel.Request(model_name='r2d2'), 1,
                check=lambda r: r.success)
            samples['trigger'] = observer.timed_calls(
                Trigger, '/benchmark_trivial/trigger', lambda _: Trigger.Request(), 1,
                check=lambda r: r.success)
            if index >= 3:
                for key, values in samples.items():
                    result[key] += values
        if with_reset:
            observer.call(SpawnModel, '/mujoco/spawn_urdf_model', spawn_request(0))
            result['reset_world'] = observer.timed_calls(
                Empty, '/mujoco/reset_world', lambda _: Empty.Request(), calls)
        return result
    finally:
        executor.shutdown(timeout_sec=5.0)
        thread.join(timeout=5.0)
        world.destroy_node()
        trivial.node.destroy_node()


@contextlib.contextmanager
def quiet_console(path):
    """Send this process's stderr (where in-process nodes log) to a file for a while."""
    sys.stderr.flush()
    saved = os.dup(2)
    with open(path, 'a') as log_file:
        os.dup2(log_file.fileno(), 2)
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)


def round_trip_table(observer, config):
    """Spawn, delete and reset_world through the services against their floors."""
    core = core_round_trips(1, config.calls)
    with quiet_console(config.log_path):
        node = node_round_trips(observer, 1, config.calls)
    trivial_p50 = percentiles(node['trigger'])[0]
    table = Table('round_trips', 'Service round trips, world with 1 tinybot in real time (ms)', [
        ('operation', ''), ('calls', 'd'), ('p50', '.2f'), ('p95', '.2f'), ('p99', '.2f'),
        ('core p50', '.2f'), ('core p99', '.2f'), ('Trigger p50', '.2f'),
        ('limit p50', '.2f'), ('within', '')])
    for operation, service in (('spawn', 'spawn_urdf_model (R2-D2)'),
                               ('delete', 'delete_model (R2-D2)'),
                               ('reset_world', 'reset_world')):
        p50, p95, p99 = percentiles(node[operation])
        core_p50, _, core_p99 = percentiles(core[operation])
        limit = trivial_p50 + 2.0 * core_p50
        table.rows.append([service, len(node[operation]), p50, p95, p99, core_p50, core_p99,
                           trivial_p50, limit, p50 <= limit])
    p50, p95, p99 = percentiles(node['trigger'])
    table.rows.append(['Trigger (trivial)', len(node['trigger']), p50, p95, p99, 0.0, 0.0,
                       trivial_p50, trivial_p50, True])
    table.note = ('limit p50 = Trigger p50 + 2 x core p50; core = the same operation on '
                  'World in-process, no ROS; Trigger = trivial service on the same executor')
    return table


def growth_table(observer, config):
    """Measure the cost of one spawn as the world fills up with tinybots."""
    table = Table('spawn_growth', 'Spawn R2-D2 as the world grows (ms)', [
        ('models present', 'd'), ('calls', 'd'), ('spawn p50', '.2f'), ('core spawn p50', '.2f'),
        ('delete p50', '.2f'), ('core delete p50', '.2f'), ('Trigger p50', '.2f'),
        ('spawn limit', '.2f'), ('within', ''), ('delete limit', '.2f'), ('delete within', '')])
    for count in config.growth_counts:
        with quiet_console(config.log_path):
            node = node_round_trips(observer, count, config.growth_calls, with_reset=False,
                                    core=core_fleet(count, driving=False))
        spawn_p50, core_spawn_p50 = median_ms(node['spawn']), median_ms(node['core spawn'])
        delete_p50, core_delete_p50 = median_ms(node['delete']), median_ms(node['core delete'])
        trivial_p50 = median_ms(node['trigger'])
        spawn_limit = core_spawn_p50 + 2.0 * trivial_p50
        delete_limit = core_delete_p50 + 2.0 * trivial_p50
        table.rows.append([count, len(node['spawn']), spawn_p50, core_spawn_p50, delete_p50,
                           core_delete_p50, trivial_p50, spawn_limit, spawn_p50 <= spawn_limit,
                           delete_limit, delete_p50 <= delete_limit])
    table.note = ('every spawn recompiles the whole model, so its cost grows with the world; '
                  'limit = core p50 + 2 x Trigger p50 (the service may cost two trivial round '
                  'trips more than the same operation on World). Each round times the core '
                  'spawn and delete (a ROS-free World with the same models, the world of the '
                  'node paused meanwhile), then the service spawn and delete, then one Trigger')
    return table


# ------------------------------------------------------------------ speed and real time


class RawFleet:
    """The fleet compiled into a ROS-free World in this process, stepped by bare mj_step."""

    def __init__(self, count):
        self.world = core_fleet(count, driving=True)
        # The world ends the wheels' acceleration ramps between steps; bare mj_step would not.
        self.world.step(round(1.0 / self.world.timestep))

    def window(self, seconds):
        """Step for seconds of wall time; return simulated s per wall s and per CPU s."""
        model, data = self.world.model, self.world.data
        chunk = 50
        steps = 0
        start, cpu_start = time.perf_counter(), time.thread_time()
        end = start + seconds
        while True:
            mujoco.mj_step(model, data, chunk)
            steps += chunk
            now = time.perf_counter()
            if now >= end:
                break
        simulated = steps * model.opt.timestep
        return simulated / (now - start), simulated / max(time.thread_time() - cpu_start, 1e-9)


def process_cpu_time(pid):
    """Return the CPU time (user and system, every thread) a process has used, in s."""
    with open(f'/proc/{pid}/stat') as stat_file:
        fields = stat_file.read().rsplit(')', 1)[1].split()
    # utime and stime are fields 14 and 15 of proc(5); fields[0] here is field 3.
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


class FleetWorld:
    """
    mujoco_world run as a process with a driving fleet, measured window by window.

    Simulation time is read from get_model_state stamps at both ends of a window (each taken
    at the middle of its round trip), so the measurement does not depend on keeping up with
    /clock. /clock and bot0's odom are subscribed to and counted, so the world really delivers
    them; every robot's odometry is integrated and would be published to any subscriber.
    """

    def __init__(self, observer, count, real_time_factor, **parameters):
        from nav_msgs.msg import Odometry
        from rosgraph_msgs.msg import Clock
        self._observer = observer
        self.names = fleet_names(count)
        self.process = NodeProcess('mujoco_world', node_name='mujoco', parameters={
            **fleet_parameters(count, real_time_factor), **parameters})
        self.fleet = None
        self._subscriptions = []
        try:
            wait_for_world(observer, self.process, self.names[0])
            self._clock_count, clock_sub = observer.counter(Clock, '/clock')
            self._odom_count, odom_sub = observer.counter(Odometry, f'/{self.names[0]}/odom')
            self._subscriptions = [clock_sub, odom_sub]
            self.fleet = Fleet(observer, count)
            self.fleet.start(self.process)
        except BaseException:
            self.close()
            raise

    def window(self, seconds):
        """Drive for seconds; return sim s per wall s and per CPU s, /clock and odom msgs/s."""
        observer, pid = self._observer, self.process.process.pid
        sim_start, wall_start, _ = sim_time_sample(observer, self.names[0])
        cpu_start = process_cpu_time(pid)
        clocks, odoms = self._clock_count[0], self._odom_count[0]
        self.fleet.drive_for(seconds)
        sim_end, wall_end, state = sim_time_sample(observer, self.names[0])
        cpu = process_cpu_time(pid) - cpu_start
        self.process.check()
        if state.twist.angular.z < 0.8 * DRIVE_ANGULAR_Z:
            raise BenchmarkError(f'{self.names[0]} stopped turning during the measurement')
        simulated, wall = sim_end - sim_start, wall_end - wall_start
        return (simulated / wall, simulated / max(cpu, 1e-9),
                (self._clock_count[0] - clocks) / wall, (self._odom_count[0] - odoms) / wall)

    def physics(self, service):
        """Call pause_physics or unpause_physics."""
        from std_srvs.srv import Empty
        self._observer.call(Empty, '/mujoco/' + service, Empty.Request())

    def close(self):
        """Stop the process and wait until its services have left the graph."""
        from srv_interfaces.srv import GetModelState
        if self.fleet is not None:
            self.fleet.destroy()
        for subscription in self._subscriptions:
            self._observer.node.destroy_subscription(subscription)
        self.process.stop()
        wait_until_gone(self._observer, GetModelState, '/mujoco/get_model_state')

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()


def alternating_windows(observer, count, real_time_factor, window, config):
    """
    Alternate windows of bare mj_step (world paused) and of the world node, round by round.

    Adjacent windows see the same load on a shared machine. Yield bare mj_step's RawFleet.window
    figures and the world's FleetWorld.window figures of each round.
    """
    raw = RawFleet(count)
    with FleetWorld(observer, count, real_time_factor) as world:
        world.fleet.drive_for(config.warm_up)
        for _ in range(config.speed_rounds):
            world.physics('pause_physics')
            raw_figures = raw.window(config.speed_window)
            world.physics('unpause_physics')
            world.fleet.drive_for(config.speed_settle)
            yield raw_figures, world.window(window)


def free_running_rounds(observer, count, config):
    """Return the free-running world node's figures against bare mj_step, medians of rounds."""
    rounds = []
    for (raw_speed, raw_cpu), (node_speed, node_cpu, clock_rate, odom_rate) in \
            alternating_windows(observer, count, 0.0, config.speed_window, config):
        rounds.append((node_speed, raw_speed, node_speed / raw_speed, node_cpu / raw_cpu,
                       clock_rate, odom_rate))
    return [statistics.median(column) for column in zip(*rounds)]


def real_time_rounds(observer, count, config):
    """
    Return the world node's figures in real time against bare mj_step, medians of rounds.

    They are the achieved factor, the world's CPU share (%), the CPU share bare mj_step of the
    same fleet needs for real time (%), the ratio of the two in each round, and the /clock and
    odom rates.
    """
    rounds = []
    for (_, raw_per_cpu_second), (factor, per_cpu_second, clock_rate, odom_rate) in \
            alternating_windows(observer, count, 1.0, config.real_time_window, config):
        world_cpu, raw_cpu = 100.0 * factor / per_cpu_second, 100.0 / raw_per_cpu_second
        rounds.append((factor, world_cpu, raw_cpu, world_cpu / raw_cpu, clock_rate, odom_rate))
    return [statistics.median(column) for column in zip(*rounds)]


def speed_tables(observer, config):
    """Free-running speed against raw mj_step, and the real-time factor achieved."""
    speed = Table('free_running', 'Free-running speed, real_time_factor 0 (simulated s per '
                  'wall s)', [
                      ('robots', 'd'), ('world node', '.1f'), ('raw mj_step', '.1f'),
                      ('ratio', '.3f'), ('target ratio', '.1f'), ('within', ''),
                      ('CPU-time ratio', '.3f'), ('/clock msgs/s', '.0f'),
                      ('bot0 odom msgs/s', '.0f')])
    real_time = Table('real_time', 'Real time, real_time_factor 1', [
        ('robots', 'd'), ('achieved factor', '.4f'), ('error %', '.2f'), ('limit %', '.1f'),
        ('within', ''), ('raw mj_step x real time', '.1f'), ('world CPU %', '.0f'),
        ('raw mj_step CPU %', '.1f'), ('CPU ratio', '.2f'), ('CPU limit ratio', '.1f'),
        ('CPU within', ''),
        ('/clock msgs/s', '.0f'), ('bot0 odom msgs/s', '.0f')])
    for count in config.robot_counts:
        node, raw, ratio, cpu_ratio, clock_rate, odom_rate = free_running_rounds(
            observer, count, config)
        target = 0.7 if count == 1 else 0.8
        speed.rows.append([count, node, raw, ratio, target, ratio >= target, cpu_ratio,
                           clock_rate, odom_rate])
        factor, world_cpu, raw_cpu_percent, cpu_ratio, clock_rate, odom_rate = \
            real_time_rounds(observer, count, config)
        error = 100.0 * (factor - 1.0)
        real_time.rows.append([count, factor, error, 1.0, abs(error) <= 1.0, raw, world_cpu,
                               raw_cpu_percent, cpu_ratio, CPU_LIMIT_RATIO,
                               cpu_ratio <= CPU_LIMIT_RATIO, clock_rate, odom_rate])
    speed.note = ('world node: the mujoco_world executable in its own process, every robot '
                  'driving on /cmd_vel, /clock and bot0/odom subscribed to here (msgs/s: what '
                  'arrived per wall s). raw mj_step: the same fleet compiled in this process, '
                  'no ROS, stepped while the world node is paused. Medians of '
                  f'{config.speed_rounds} alternating rounds of {config.speed_window} s. '
                  'CPU-time ratio: the same per CPU second used (every thread of the world '
                  'process), which other load on a shared machine skews less. Target ratio '
                  '0.7 with 1 robot, 0.8 with more.')
    real_time.note = ('achieved factor over each window from get_model_state stamps; raw '
                      'mj_step x real time is how much faster than real time the physics '
                      'alone could run (from the free-running rows); world CPU %: CPU time '
                      'of the world process per wall second; raw mj_step CPU %: the CPU share '
                      'bare mj_step of the same fleet needs for real time (its simulated s per '
                      'CPU s, stepped in this process while the world node is paused); CPU '
                      'ratio: world CPU over raw mj_step CPU, the two windows of a round '
                      f'taken together; at most {CPU_LIMIT_RATIO} (the target is set for '
                      f'{CPU_TARGET_ROBOTS} robots; with fewer, /clock at 250 Hz and a tick '
                      'every 20 ms cost more than the physics). Medians of '
                      f'{config.speed_rounds} alternating rounds: {config.speed_window} s of '
                      f'bare mj_step, then {config.real_time_window} s of the world node')
    return speed, real_time


# ------------------------------------------------------------------------ start-up


def startup_table(observer, config):
    """Process start of mujoco_world until every /mujoco/ service answers."""
    from srv_interfaces.srv import DeleteModel, GetModelList, GetModelState, SetModelState
    from srv_interfaces.srv import SpawnModel
    from std_srvs.srv import Empty
    types = {'spawn_urdf_model': SpawnModel, 'delete_model': DeleteModel,
             'get_model_list': GetModelList, 'get_model_state': GetModelState,
             'set_model_state': SetModelState}
    services = [(types.get(name, Empty), '/mujoco/' + name) for name in WORLD_SERVICES]
    for srv_type, name in services:
        observer.client(srv_type, name)  # discovery starts before the process does
    times, cpu_times = [], []
    for _ in range(config.startup_runs):
        wait_until_gone(observer, GetModelList, '/mujoco/get_model_list')
        start = time.monotonic()
        with NodeProcess('mujoco_world') as process:
            for srv_type, name in services:
                observer.wait_for_service(srv_type, name, process=process)
            response = observer.call(GetModelList, '/mujoco/get_model_list',
                                     GetModelList.Request())
            times.append(time.monotonic() - start)
            cpu_times.append(process_cpu_time(process.process.pid))
            if list(response.model_names) != ['tinybot']:
                raise BenchmarkError(f'unexpected start-up models {response.model_names}')
    wait_until_gone(observer, GetModelList, '/mujoco/get_model_list')
    imports = []
    for _ in range(max(1, min(3, config.startup_runs))):
        start = time.monotonic()
        subprocess.run([sys.executable, '-c', 'import service_tutorial.world_node.node'],
                       check=True)
        imports.append(time.monotonic() - start)
    table = Table('startup', 'Start-up: mujoco_world process start to every /mujoco/ service '
                  'answering (s)', [
                      ('runs', 'd'), ('p50', '.3f'), ('max', '.3f'), ('CPU s p50', '.3f'),
                      ('imports alone p50', '.3f'), ('target', '.1f'), ('within', '')])
    p50 = statistics.median(times)
    table.rows.append([len(times), p50, max(times), statistics.median(cpu_times),
                       statistics.median(imports), 1.5, p50 < 1.5])
    table.note = ('CPU s: CPU time the world process had used when ready; imports alone: wall '
                  'time of a fresh interpreter importing service_tutorial.world_node.node (rclpy, '
                  'MuJoCo, yourdfpy and trimesh), the floor of any start-up')
    return table


# ------------------------------------------------------------------------ turning


class YawTracker:
    """Unwraps yaw samples into the total angle turned; samples must be under pi apart."""

    def __init__(self, yaw):
        self.last = yaw
        self.turned = 0.0

    def add(self, yaw):
        """Add a sample; return the total turned so far."""
        step = math.remainder(yaw - self.last, 2.0 * math.pi)
        self.turned += step
        self.last = yaw
        return self.turned


def measure_turn(observer, duration, angular_vel):
    """Turn tinybot through /control_robot_angle; return the angle it really turned."""
    from service_tutorial.conversions import yaw_of
    from srv_interfaces.srv import ControlTurningMessage
    _, _, state = sim_time_sample(observer, 'tinybot')
    tracker = YawTracker(yaw_of(state.pose.orientation))
    future = observer.call_async(ControlTurningMessage, '/control_robot_angle',
                                 ControlTurningMessage.Request(time_duration=duration,
                                                               angular_vel=angular_vel))
    deadline = time.monotonic() + 60.0 + 10.0 * duration
    while not future.done():
        if time.monotonic() > deadline:
            raise BenchmarkError('/control_robot_angle did not answer')
        _, _, state = sim_time_sample(observer, 'tinybot')
        tracker.add(yaw_of(state.pose.orientation))
        time.sleep(0.002)
    if not future.result().success:
        raise BenchmarkError(f'/control_robot_angle refused {duration} s at {angular_vel} rad/s')
    end, _, _ = sim_time_sample(observer, 'tinybot')
    while True:
        now, _, state = sim_time_sample(observer, 'tinybot')
        tracker.add(yaw_of(state.pose.orientation))
        if now >= end + SETTLE_TIME and abs(state.twist.angular.z) < 1e-3:
            return tracker.turned
        if time.monotonic() > deadline:
            raise BenchmarkError('tinybot did not come to rest after its turn')
        time.sleep(0.005)


def turning_world(real_time_factor):
    """Start the default world and the turning server on simulation time."""
    world = NodeProcess('mujoco_world', node_name='mujoco',
                        parameters={'real_time_factor': float(real_time_factor)})
    try:
        server = NodeProcess('robot_turning_server', ros_args=['-p', 'use_sim_time:=true'])
    except BaseException:
        world.stop()
        raise
    return world, server


def run_turns(observer, real_time_factor, points):
    """Run a list of (duration, angular_vel) turns in one fresh world; return the rows."""
    from srv_interfaces.srv import ControlTurningMessage, GetModelState
    world, server = turning_world(real_time_factor)
    rows = []
    try:
        wait_for_world(observer, world, 'tinybot')
        observer.wait_for_service(ControlTurningMessage, '/control_robot_angle', process=server)
        # Not measured: the two processes have just started, and a first command can go out
        # before the server's cmd_vel publisher and the world's subscription have met.
        measure_turn(observer, 1, 0.5)
        for duration, angular_vel in points:
            commanded = duration * angular_vel
            measured = measure_turn(observer, duration, angular_vel)
            error = 100.0 * (measured - commanded) / commanded
            rows.append([real_time_factor, duration, angular_vel, commanded, measured, error,
                         TURNING_TARGET_PERCENT, abs(error) < TURNING_TARGET_PERCENT])
            world.check()
            server.check()
    finally:
        server.stop()
        world.stop()
    wait_until_gone(observer, GetModelState, '/mujoco/get_model_state')
    wait_until_gone(observer, ControlTurningMessage, '/control_robot_angle')
    return rows


def turning_tables(observer, config):
    """Measure the turning grid at one real_time_factor, and one turn at several."""
    columns = [('real_time_factor', '.0f'), ('duration s', 'd'), ('angular_vel rad/s', '.1f'),
               ('commanded rad', '.3f'), ('measured rad', '.4f'), ('error %', '.2f'),
               ('limit %', '.1f'), ('within', '')]
    grid = Table('turning', '/control_robot_angle accuracy (robot_turning_server, '
                 'use_sim_time)', list(columns))
    grid.rows = run_turns(observer, config.turning_rtf, [
        (duration, velocity) for duration in config.durations
        for velocity in config.velocities])
    grid.note = ('measured: unwrapped yaw of tinybot from /mujoco/get_model_state (ground '
                 'truth), sampled during the turn and after it came to rest')
    tables = [grid]
    if config.turning_check_rtfs:
        check = Table('turning_check', 'One turn at several real_time_factors (0: '
                      'free-running)', list(columns))
        for factor in config.turning_check_rtfs:
            check.rows += run_turns(observer, factor, [config.turning_check_point])
        check.note = ('the turning server stops the robot on a /clock-driven timer; the '
                      'world runs on while the stop travels, so the error grows with the '
                      'factor')
        tables.append(check)
    return tables


# ------------------------------------------------------------ core, camera and answers


def core_table(config):
    """Measure spawning into and stepping a World in this process, no ROS, against limits."""
    from service_tutorial.sim.world import World
    world = World()
    world.spawn_urdf_file('tinybot', model_path('tinybot'))
    world.step(250)
    spawns = []
    for index in range(config.core_spawns):
        start = time.perf_counter()
        world.spawn_urdf_file(f'r2d2_{index}', model_path('r2d2'),
                              position=(2.0 + index, 0.0, 0.0))
        spawns.append(time.perf_counter() - start)
    model, data = world.model, world.data
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    raw = mujoco.MjData(model)
    state = np.empty(mujoco.mj_stateSize(model, kind))
    mujoco.mj_getState(model, data, state, kind)
    mujoco.mj_setState(model, raw, state, kind)
    world_best = raw_best = math.inf
    for _ in range(config.step_rounds):
        start = time.perf_counter()
        world.step(config.step_count)
        world_best = min(world_best, time.perf_counter() - start)
        start = time.perf_counter()
        mujoco.mj_step(model, raw, config.step_count)
        raw_best = min(raw_best, time.perf_counter() - start)
    spawn_p50, ratio = median_ms(spawns), world_best / raw_best
    table = Table('core', 'World in this process, no ROS: tinybot, then R2-D2s beside it', [
        ('figure', ''), ('measured', '.3f'), ('limit', '.2f'), ('within', '')])
    table.rows = [
        [f'spawn R2-D2 p50 of {len(spawns)} (ms)', spawn_p50, 50.0, spawn_p50 < 50.0],
        [f'World.step / bare mj_step time, best of {config.step_rounds} x '
         f'{config.step_count} steps', ratio, 1.5, ratio < 1.5]]
    table.note = ('the world grows by one R2-D2 a spawn; World.step and mj_step step the same '
                  'model from the same state (they stay bit for bit equal, see test_world.py)')
    return table


def spawn_cost_table(config):
    """Spawn and delete on a World in this process against MuJoCo's own path, no ROS."""
    def make_world(present):
        return core_fleet(present, driving=False)

    table = Table('spawn_cost', "Spawn and delete on World, no ROS, against MuJoCo's own path",
                  list(spawn_cost.COLUMNS))
    model_dir = os.path.dirname(model_path('r2d2'))
    for present in config.cost_counts:
        table.rows += spawn_cost.spawn_rows(make_world, read_model, model_dir, fleet_position,
                                            present, config.cost_calls)
    table.rows.append(spawn_cost.box_row(make_world, config.box_count))
    table.note = spawn_cost.NOTE
    return table


def wait_for_count(counter, process, what, *, timeout=30.0):
    """Wait until a message counter has counted one; fail early if the process exits."""
    deadline = time.monotonic() + timeout
    while counter[0] == 0:
        process.check()
        if time.monotonic() > deadline:
            raise BenchmarkError(f'no {what} within {timeout} s')
        time.sleep(0.01)


def camera_table(observer, config):
    """Measure the pace the world keeps while its camera streams to a subscriber."""
    from sensor_msgs.msg import Image
    from srv_interfaces.srv import GetModelState
    parameters = {'camera_enabled': True, 'camera_rate': 5.0, 'camera_width': 160,
                  'camera_height': 120}
    with NodeProcess('mujoco_world', node_name='mujoco', parameters=parameters) as process:
        wait_for_world(observer, process, 'tinybot')
        frames, subscription = observer.counter(Image, '/mujoco/camera/image_raw')
        try:
            wait_for_count(frames, process, 'camera image')
            first = frames[0]
            sim_start, wall_start, _ = sim_time_sample(observer, 'tinybot')
            time.sleep(config.camera_window)
            sim_end, wall_end, _ = sim_time_sample(observer, 'tinybot')
            count = frames[0] - first
        finally:
            observer.node.destroy_subscription(subscription)
    wait_until_gone(observer, GetModelState, '/mujoco/get_model_state')
    simulated = max(sim_end - sim_start, 1e-9)
    factor = simulated / (wall_end - wall_start)
    table = Table('camera', 'Camera streaming 160x120 at 5 Hz to a subscriber, '
                  'real_time_factor 1', [
                      ('achieved factor', '.3f'), ('frames per simulated s', '.2f'),
                      ('limit factor', '.1f'), ('within', '')])
    table.rows.append([factor, count / simulated, 0.3, factor > 0.3])
    table.note = ('the mujoco_world executable; frames are rendered on the stepping thread, '
                  'so a slow (software) renderer holds the simulation back')
    return table


# ------------------------------------------------------------------------ sensors


def cpu_time_per_call(function, repeats):
    """Return the CPU time of this thread one call of function took, in s."""
    start = time.thread_time()
    for _ in range(repeats):
        function()
    return (time.thread_time() - start) / repeats


def sensor_world(samples=360):
    """Return a World in the yard holding tinybot, its laser given samples beams."""
    from service_tutorial.sim.world import World
    world = World(scenery=model_path('yard'))
    urdf = read_model('tinybot').replace('<samples>360</samples>', f'<samples>{samples}</samples>')
    world.spawn_urdf('tinybot', urdf, base_dir=os.path.dirname(model_path('tinybot')))
    world.step(250)
    return world


def scan_row(samples, config):
    """Time one scan of tinybot's laser, and one bare mj_multiRay of the same rays."""
    from service_tutorial.sim.plugins.ray_sensor import RAY_GEOM_GROUPS, RaySensor
    world = sensor_world(samples)
    laser = world.models['tinybot'].plugin(RaySensor)
    laser.set_active(True)
    world.step(1)
    model, data, site = world.model, world.data, laser.site_id
    origin = data.site_xpos[site].copy()
    directions = (laser.config.directions @ data.site_xmat[site].reshape(3, 3).T).ravel()
    geom_ids, distances = np.zeros(samples, dtype=np.int32), np.zeros(samples)

    def bare():
        mujoco.mj_multiRay(model, data, origin, directions, RAY_GEOM_GROUPS, 1, -1, geom_ids,
                           distances, None, samples, laser.config.range_max)
    scans, rays = [], []
    for _ in range(3):  # alternating, so both see the same load; the best of each
        scans.append(cpu_time_per_call(laser.read, config.scan_repeats))
        rays.append(cpu_time_per_call(bare, config.scan_repeats))
    scan, ray = min(scans) * 1e6, min(rays) * 1e6
    return [f'{samples}-beam scan, tinybot in the yard (us)', scan, ray, scan / ray, 1.5,
            scan / ray <= 1.5]


def camera_frame_row(config):
    """Time one frame of tinybot's camera (320x240), and one of a bare mujoco.Renderer."""
    from service_tutorial.sim.plugins.camera_sensor import CameraSensor
    from service_tutorial.sim.rendering import prefer_headless_gl
    world = sensor_world()
    camera = world.models['tinybot'].plugin(CameraSensor)
    camera.set_active(True)
    world.step(1)  # the first frame makes the renderer and its GL context
    config_camera = camera.config
    prefer_headless_gl()
    renderer = mujoco.Renderer(world.model, config_camera.height, config_camera.width)
    name = world.models['tinybot'].scoped(config_camera.site_name(CameraSensor.kind))

    def bare():
        renderer.update_scene(world.data, camera=name)
        renderer.render()
    frames, bare_frames = [], []
    try:
        bare()
        for _ in range(config.camera_frames):
            start = time.perf_counter()
            camera.read()
            frames.append(time.perf_counter() - start)
            start = time.perf_counter()
            bare()
            bare_frames.append(time.perf_counter() - start)
    finally:
        renderer.close()
        camera.close()
    frame, bare_frame = median_ms(frames), median_ms(bare_frames)
    return [f'{config_camera.width}x{config_camera.height} robot camera frame (ms)', frame,
            bare_frame, frame / bare_frame, 1.5, frame / bare_frame <= 1.5]


def laser_speed_rows(observer, config):
    """Free-running speed of tinybot with its 5 Hz laser listened to, and without."""
    from sensor_msgs.msg import LaserScan
    rounds = []
    with FleetWorld(observer, 1, 0.0, scenery='yard.urdf') as world:
        world.fleet.drive_for(config.warm_up)
        for _ in range(config.speed_rounds):
            quiet, quiet_per_cpu = world.window(config.speed_window)[:2]
            scans, subscription = observer.counter(LaserScan, f'/{world.names[0]}/scan')
            try:
                wait_for_count(scans, world.process, 'scan')
                listened, listened_per_cpu = world.window(config.speed_window)[:2]
            finally:
                observer.node.destroy_subscription(subscription)
            rounds.append((listened, quiet, listened_per_cpu, quiet_per_cpu))
    listened, quiet, listened_per_cpu, quiet_per_cpu = (
        statistics.median(column) for column in zip(*rounds))
    return [['free-running speed, 360-beam laser at 5 Hz listened to / not (sim s per wall '
             's)', listened, quiet, listened / quiet, 0.8, listened / quiet >= 0.8],
            ['the same per CPU second of the world process (sim s per CPU s)',
             listened_per_cpu, quiet_per_cpu, listened_per_cpu / quiet_per_cpu, 0.8,
             listened_per_cpu / quiet_per_cpu >= 0.8]]


def sensor_table(observer, config):
    """Measure the sensors' cost against bare MuJoCo calls, and against not listening."""
    table = Table('sensors', "Sensors: tinybot's laser and camera against bare MuJoCo", [
        ('figure', ''), ('sensor', '.3f'), ('bare', '.3f'), ('ratio', '.3f'),
        ('limit', '.2f'), ('within', '')])
    table.rows = [scan_row(360, config), scan_row(720, config), camera_frame_row(config),
                  *laser_speed_rows(observer, config)]
    table.note = ('scans: CPU time of RaySensor.read() (cast, own geoms hidden, REP 117 '
                  'ranges, noise) against mj_multiRay of the same rays on the same model, best '
                  f'of 3 x {config.scan_repeats}; ratio at most the limit. Camera: median wall '
                  f'time of {config.camera_frames} frames of CameraSensor.read() against '
                  'update_scene() and render() of a bare mujoco.Renderer at the same camera; '
                  'ratio at most the limit. Speed: mujoco_world driving tinybot (bot0) in the '
                  'yard, free-running, with a subscriber to bot0/scan here against none, '
                  f'medians of {config.speed_rounds} alternating rounds of '
                  f'{config.speed_window} s; ratio at least the limit. Free-running, a '
                  'listened sensor is held to its rate in wall time too, like every stream; '
                  'per CPU second is the steadier figure on a shared machine.')
    return table


def answers_table(observer, config):
    """Time how soon a missing service is reported and a turn without turning answered."""
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from service_tutorial.lesson.model_services import delete_model, ServiceUnavailableError
    from service_tutorial.lesson.robot_turning_server import RobotTurningServer
    from srv_interfaces.srv import ControlTurningMessage
    table = Table('answers', 'Answers that need no simulation (s)', [
        ('call', ''), ('took', '.3f'), ('limit', '.1f'), ('within', '')])
    script = Node('benchmark_script', namespace='/nowhere')  # no world in this namespace
    try:
        start = time.monotonic()
        try:
            delete_model(script, 'r2d2', timeout=0.5)
            raise BenchmarkError('delete_model found a world under /nowhere')
        except ServiceUnavailableError:
            took = time.monotonic() - start
    finally:
        script.destroy_node()
    table.rows.append(['model_services.delete_model, no world, timeout 0.5 s', took, 1.5,
                       took < 1.5])
    with quiet_console(config.log_path):
        server = RobotTurningServer()
        executor = SingleThreadedExecutor()
        executor.add_node(server)
        thread = threading.Thread(target=executor.spin, daemon=True)
        thread.start()
        try:
            observer.wait_for_service(ControlTurningMessage, '/control_robot_angle')
            for what, duration, velocity, success in (
                    ('refused: 1 s at 1.6 rad/s', 1, 1.6, False),
                    ('zero-length turn', 0, 1.0, True)):
                start = time.monotonic()
                response = observer.call(ControlTurningMessage, '/control_robot_angle',
                                         ControlTurningMessage.Request(
                                             time_duration=duration, angular_vel=velocity))
                took = time.monotonic() - start
                if response.success != success:
                    raise BenchmarkError(f'/control_robot_angle {what}: success '
                                         f'{response.success}')
                table.rows.append([f'/control_robot_angle, {what}', took, 2.0, took < 2.0])
        finally:
            executor.shutdown(timeout_sec=5.0)
            thread.join(timeout=5.0)
            server.destroy_node()
    wait_until_gone(observer, ControlTurningMessage, '/control_robot_angle')
    table.note = ('the turning server in this process, on an executor thread of its own; '
                  'neither answer waits for a turn')
    return table


# ------------------------------------------------------------------------ report


def targets(tables):
    """Return the targets of issues 5 and 15 with their measured values and whether they hold."""
    rows = []
    by_key = {table.key: table for table in tables}
    if 'round_trips' in by_key:
        spawn = by_key['round_trips'].rows[0]
        rows.append(['spawn p50 <= Trigger p50 + 2 x core spawn p50 (ms)', spawn[2], spawn[8],
                     spawn[9]])
    if 'spawn_growth' in by_key:
        for row in by_key['spawn_growth'].rows:
            rows.append([f'service spawn p50 <= core + 2 x Trigger, {row[0]} present (ms)',
                         row[2], row[7], row[8]])
            rows.append([f'service delete p50 <= core + 2 x Trigger, {row[0]} present (ms)',
                         row[4], row[9], row[10]])
    if 'spawn_cost' in by_key:
        for row in by_key['spawn_cost'].rows:
            rows.append([f'World / MuJoCo, {row[0]}, {row[1]} present', row[5], row[6],
                         row[7]])
    if 'free_running' in by_key:
        for row in by_key['free_running'].rows:
            rows.append([f'free-running ratio to raw mj_step, {row[0]} robot(s)', row[3],
                         row[4], row[5]])
    if 'real_time' in by_key:
        for row in by_key['real_time'].rows:
            rows.append([f'real-time factor error %, {row[0]} robot(s)', abs(row[2]), row[3],
                         row[4]])
            if row[0] == CPU_TARGET_ROBOTS:
                rows.append([f'real-time world CPU / raw mj_step CPU, {row[0]} robot(s)',
                             row[8], row[9], row[10]])
    if 'startup' in by_key:
        row = by_key['startup'].rows[0]
        rows.append(['start-up to services ready p50 (s)', row[1], row[5], row[6]])
    if 'turning' in by_key:
        worst = max(abs(row[5]) for row in by_key['turning'].rows)
        rows.append(['worst turning error % on the grid', worst, TURNING_TARGET_PERCENT,
                     worst < TURNING_TARGET_PERCENT])
    return Table('targets', 'Targets', [('target', ''), ('measured', '.3f'), ('limit', '.3f'),
                                        ('holds', '')], rows)


SECTIONS = ('round_trips', 'spawn_growth', 'speed', 'startup', 'turning', 'core', 'spawn_cost',
            'camera', 'sensors', 'answers')


def run(config, *, sections=SECTIONS, report=print):
    """Measure the selected sections; rclpy must be initialised. Return the tables."""
    observer = Observer()
    tables = []

    def add(*new_tables):
        for table in new_tables:
            tables.append(table)
            report(table.render() + '\n')
    try:
        # Start-up first: once this process's DDS participant has made and dropped the
        # thousands of topics of the in-process sections, its new service clients take a
        # second longer to match a new world (1.9 s against 0.85 s), whatever the world does.
        if 'startup' in sections:
            add(startup_table(observer, config))
        if 'round_trips' in sections:
            add(round_trip_table(observer, config))
        if 'spawn_growth' in sections:
            add(growth_table(observer, config))
        if 'speed' in sections:
            add(*speed_tables(observer, config))
        if 'turning' in sections:
            add(*turning_tables(observer, config))
        if 'core' in sections:
            add(core_table(config))
        if 'spawn_cost' in sections:
            add(spawn_cost_table(config))
        if 'camera' in sections:
            add(camera_table(observer, config))
        if 'sensors' in sections:
            add(sensor_table(observer, config))
        if 'answers' in sections:
            add(answers_table(observer, config))
    finally:
        observer.close()
    add(targets(tables))
    return tables


def write_json(path, tables, config, info):
    """Write the report as JSON, with the machine and the run's configuration."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    document = {'machine': info, 'config': config.__dict__,
                'tables': {table.key: table.as_dict() for table in tables}}
    with open(path, 'w') as json_file:
        json.dump(document, json_file, indent=2)
        json_file.write('\n')


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
