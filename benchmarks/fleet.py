"""The package's models and fleets of driving tinybots, in a world process or in this one."""

import os
import time

from harness import BenchmarkError, ClosedOnExit, NodeProcess, sim_time_sample
from harness import wait_for_world, wait_until, wait_until_world_gone
import mujoco
from service_tutorial.testing.spawns import spawn_file

PACKAGE = 'service_tutorial'
# Fleet layout: ten robots to a row, far enough apart that their circles never touch.
SPACING = 1.5
# What every robot of a fleet is told on cmd_vel: circles of 0.4 m radius.
DRIVE_LINEAR_X = 0.2
DRIVE_ANGULAR_Z = 0.5


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
        spawn_file(world, name, path, position=fleet_position(index))
        if driving:
            world.models[name].drive().command_velocity(DRIVE_LINEAR_X, DRIVE_ANGULAR_Z)
    return world


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
        wait_until(lambda: all(p.get_subscription_count() > 0 for p in self.publishers),
                   'the world did not subscribe to every cmd_vel', timeout=timeout,
                   process=process)
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


class FleetWorld(ClosedOnExit):
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
        observer = self._observer
        sim_start, wall_start, _ = sim_time_sample(observer, self.names[0])
        cpu_start = self.process.cpu_time()
        clocks, odoms = self._clock_count[0], self._odom_count[0]
        self.fleet.drive_for(seconds)
        sim_end, wall_end, state = sim_time_sample(observer, self.names[0])
        cpu = self.process.cpu_time() - cpu_start
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
        if self.fleet is not None:
            self.fleet.destroy()
        for subscription in self._subscriptions:
            self._observer.node.destroy_subscription(subscription)
        self.process.stop()
        wait_until_world_gone(self._observer)
