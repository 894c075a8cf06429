"""Turning accuracy: robot_turning_server turning tinybot in mujoco_world, two processes."""

import math
import time

from harness import BenchmarkError, NodeProcess, sim_time_sample, wait_for_world
from harness import wait_until_gone, wait_until_world_gone
from report import Table, TURNING_TARGET_PERCENT

# After a turn, how long (simulated s) the robot is given to come to rest before measuring.
SETTLE_TIME = 0.5


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
    from srv_interfaces.srv import ControlTurningMessage
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
    wait_until_world_gone(observer)
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
        check.note = ('the turning server starts and stops the robot right after a /clock '
                      'message; the world takes commands at its ticks, which end where '
                      'odometry falls due, so a turn lasts what the server counted at any '
                      'factor; free-running, the world runs on while a command travels')
        tables.append(check)
    return tables
