"""
The MuJoCo world node: the Gazebo of this tutorial.

It steps a service_tutorial.world.World and translates ROS to and from it: the model services
under /mujoco/, /clock, and cmd_vel, odom and joint_states for every diff-drive robot.
Stepping runs in a timer of the node's single callback group, so a service callback and a
physics step never run at the same time and no locks are needed.
"""

import math
import os
import time

from ament_index_python.packages import get_package_share_directory
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.clock import Clock as WallClock, ClockType
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from service_tutorial.camera_stream import CameraStream
from service_tutorial.client_main import spin_node
from service_tutorial.conversions import fill_pose_msg, fill_time_msg, fill_twist_msg
from service_tutorial.conversions import pose_from_msg, time_msg, twist_from_msg
from service_tutorial.conversions import yaw_quaternion
from service_tutorial.world import MAX_WHEEL_RIM_SPEED, World, WorldError
from srv_interfaces.srv import DeleteModel, GetModelList, GetModelState, SetModelState
from srv_interfaces.srv import SpawnModel
from std_srvs.srv import Empty
import yaml

PACKAGE = 'service_tutorial'
# Longest stretch of wall time one timer tick may spend stepping before it lets services run.
STEP_BUDGET = 0.005
# The executor's turn between two ticks costs CPU time that grows with the node's topics (about
# 1.8 ms with 50 robots), so ticks are spaced to keep it a small share of the time. Free-running,
# a tick steps EXECUTOR_SHARE times as long as a turn (STEP_BUDGET to MAX_STEP_BUDGET); in real
# time, ticks come every REAL_TIME_SHARE turns (REAL_TIME_PERIOD to MAX_REAL_TIME_PERIOD);
# paused, there is nothing to step.
EXECUTOR_SHARE = 20.0
MAX_STEP_BUDGET = 0.05
REAL_TIME_SHARE = 5.0
REAL_TIME_PERIOD = 0.002
MAX_REAL_TIME_PERIOD = 0.02
PAUSED_STEP_PERIOD_NS = 20_000_000


def load_default_parameters():
    """Read the node's default parameters from config/world.yaml in the package share."""
    path = os.path.join(get_package_share_directory(PACKAGE), 'config', 'world.yaml')
    with open(path) as config_file:
        return yaml.safe_load(config_file)['mujoco']['ros__parameters']


def resolve_model_path(model):
    """Find a model file: an absolute path, or a file in the package's models/ folder."""
    if os.path.isabs(model):
        return model
    return os.path.join(get_package_share_directory(PACKAGE), 'models', model)


class RobotTopics:
    """The topics of one diff-drive robot: cmd_vel in, odom and joint_states out."""

    def __init__(self, node, model_name, namespace):
        prefix = namespace.rstrip('/') + '/' if namespace else ''
        self.model_name = model_name
        self.cmd_vel_sub = node.create_subscription(
            Twist, prefix + 'cmd_vel',
            lambda msg: node.cmd_vel_callback(model_name, msg), 10)
        self.odom_pub = node.create_publisher(Odometry, prefix + 'odom', 10)
        self.joint_states_pub = node.create_publisher(JointState, prefix + 'joint_states', 10)
        # Filled in and published again every time: publish() copies the message.
        self.odom_msg = Odometry()
        self.joint_states_msg = JointState()
        self._node = node

    def destroy(self):
        """Remove the robot's topics from the node."""
        self._node.destroy_subscription(self.cmd_vel_sub)
        self._node.destroy_publisher(self.odom_pub)
        self._node.destroy_publisher(self.joint_states_pub)


class MujocoWorld(Node):
    """Serves a MuJoCo world the way gazebo_ros serves Gazebo's."""

    def __init__(self, **kwargs):
        super().__init__('mujoco', **kwargs)
        defaults = load_default_parameters()
        for name, value in defaults.items():
            self.declare_parameter(name, value)
        param = self.get_parameter

        self.real_time_factor = max(0.0, param('real_time_factor').value)
        self.world = World(timestep=param('timestep').value,
                           cmd_vel_timeout=param('cmd_vel_timeout').value)
        self._clock_period = 1.0 / param('clock_publish_rate').value
        self._odom_period = 1.0 / param('odom_publish_rate').value
        self._joint_state_period = 1.0 / param('joint_state_publish_rate').value
        self._next_clock = self._next_odom = self._next_joint_states = 0.0
        # Free-running, each stream is also published at most at its rate in wall time: far
        # faster than real time, the simulation-time rates would cost more than the physics.
        self._free_running = self.real_time_factor == 0.0
        self._next_clock_wall = self._next_odom_wall = self._next_joint_states_wall = 0.0
        self._step_wall_time = 1e-5  # running estimate of one physics step, in wall seconds
        self._executor_turn = 0.0  # running estimate of the CPU time between two ticks
        self._tick_end_cpu = None
        self._clock_msg = Clock()
        self.robots = {}
        self.viewer = None

        self.clock_pub = self.create_publisher(Clock, '/clock', 10)
        self.spawn_srv = self.create_service(
            SpawnModel, '~/spawn_urdf_model', self.spawn_model_callback)
        self.delete_srv = self.create_service(
            DeleteModel, '~/delete_model', self.delete_model_callback)
        self.reset_simulation_srv = self.create_service(
            Empty, '~/reset_simulation', self.reset_simulation_callback)
        self.reset_world_srv = self.create_service(
            Empty, '~/reset_world', self.reset_world_callback)
        self.pause_srv = self.create_service(
            Empty, '~/pause_physics', self.pause_physics_callback)
        self.unpause_srv = self.create_service(
            Empty, '~/unpause_physics', self.unpause_physics_callback)
        self.model_list_srv = self.create_service(
            GetModelList, '~/get_model_list', self.get_model_list_callback)
        self.get_state_srv = self.create_service(
            GetModelState, '~/get_model_state', self.get_model_state_callback)
        self.set_state_srv = self.create_service(
            SetModelState, '~/set_model_state', self.set_model_state_callback)
        # ~/camera/image_raw, ~/camera/camera_info (camera_enabled) and ~/save_snapshot.
        self.camera_stream = CameraStream(self, self.world)

        self._spawn_start_up_models()
        if param('paused').value:
            self.world.pause()
        if param('gui').value:
            self._open_viewer()

        # Free-running stepping uses a zero-period timer: it fires on every executor turn,
        # and the executor serves pending service calls between two turns.
        period = 0.0 if self.real_time_factor == 0.0 else REAL_TIME_PERIOD
        self._anchor_real_time()
        # The world is the source of /clock, so it paces itself on the steady wall clock even
        # when use_sim_time is set (a sim-time timer would wait for its own /clock forever).
        self.step_timer = self.create_timer(
            period, self.step_callback, clock=WallClock(clock_type=ClockType.STEADY_TIME))
        self.publish_clock()
        self.get_logger().info(
            f'MuJoCo world ready: {", ".join(self.world.model_names()) or "no models"}, '
            f'timestep {self.world.timestep} s, real_time_factor {self.real_time_factor}')

    # --- stepping -----------------------------------------------------------------------------

    def _anchor_real_time(self):
        self._wall_anchor = time.monotonic()
        self._sim_anchor = self.world.time

    def step_callback(self):
        """Advance the physics to keep pace with the wall clock, then publish what is due."""
        world = self.world
        tick_start_cpu = time.thread_time()
        if self._tick_end_cpu is not None:
            # Follows the cheapest recent turns: a slow service call is not overhead.
            self._executor_turn = max(0.0, min(tick_start_cpu - self._tick_end_cpu,
                                               1.05 * self._executor_turn + 1e-6))
        period_ns = self._tick_period_ns()
        if self.step_timer.timer_period_ns != period_ns:
            self.step_timer.timer_period_ns = period_ns
        if world.paused:
            self._anchor_real_time()
        elif self.real_time_factor == 0.0:
            deadline = time.monotonic() + min(
                MAX_STEP_BUDGET, max(STEP_BUDGET, EXECUTOR_SHARE * self._executor_turn))
            while True:
                start = time.monotonic()
                if start >= deadline:
                    break
                steps = self._free_running_chunk(start, deadline)
                world.step(steps)
                self._step_wall_time += 0.5 * (
                    (time.monotonic() - start) / steps - self._step_wall_time)
                self.publish_due()
        else:
            wall_elapsed = time.monotonic() - self._wall_anchor
            target = self._sim_anchor + wall_elapsed * self.real_time_factor
            behind = int((target - world.time) / world.timestep)
            if behind > 0.1 / world.timestep:
                # More than 100 ms behind: the machine cannot keep up; do not try to catch up.
                behind = int(0.1 / world.timestep)
                self._anchor_real_time()
            while behind > 0:
                steps = min(behind, self._steps_to_next_publication())
                world.step(steps)
                behind -= steps
                self.publish_due()
        self.publish_due()
        if self.viewer is not None:
            self._sync_viewer()
        self._tick_end_cpu = time.thread_time()

    def _tick_period_ns(self):
        """Return the step timer's period for the current state, in whole milliseconds."""
        if self.world.paused:
            return PAUSED_STEP_PERIOD_NS
        if self.real_time_factor == 0.0:
            return 0
        period = min(MAX_REAL_TIME_PERIOD,
                     max(REAL_TIME_PERIOD, REAL_TIME_SHARE * self._executor_turn))
        return round(period * 1e3) * 1_000_000

    def _steps_to_next_publication(self):
        due = min(self._next_clock, self._next_odom, self._next_joint_states,
                  self.camera_stream.next_due)
        # Half a step of slack, as in publish_due().
        return max(1, math.ceil((due - self.world.time) / self.world.timestep - 0.5))

    def _free_running_chunk(self, wall, deadline):
        """Return the steps until a stream falls due (simulation and wall time) or deadline."""
        world = self.world
        per_step = max(self._step_wall_time, 1e-7)
        steps = (deadline - wall) / per_step
        for next_sim, next_wall in ((self._next_clock, self._next_clock_wall),
                                    (self._next_odom, self._next_odom_wall),
                                    (self._next_joint_states, self._next_joint_states_wall)):
            steps = min(steps, max((next_sim - world.time) / world.timestep,
                                   (next_wall - wall) / per_step))
        steps = min(steps, (self.camera_stream.next_due - world.time) / world.timestep)
        return max(1, math.ceil(steps - 0.5))

    def _wall_due(self, period):
        """Return the wall time before which a stream just published may not publish again."""
        return time.monotonic() + period if self._free_running else 0.0

    def publish_due(self):
        """Publish /clock, odometry and joint states whose time has come."""
        for name in self.world.take_removed_models():  # they kept blowing up
            robot = self.robots.pop(name, None)
            if robot is not None:
                robot.destroy()
        now = self.world.time
        # Half a step of slack: simulation time is a sum of steps and carries rounding errors.
        soon = now + 0.5 * self.world.timestep
        wall = time.monotonic()
        if soon >= self._next_clock and wall >= self._next_clock_wall:
            self.publish_clock()
        if soon >= self._next_odom and wall >= self._next_odom_wall:
            self._next_odom = now + self._odom_period
            self._next_odom_wall = self._wall_due(self._odom_period)
            for robot in self.robots.values():
                self.publish_odometry(robot, now)
        if soon >= self._next_joint_states and wall >= self._next_joint_states_wall:
            self._next_joint_states = now + self._joint_state_period
            self._next_joint_states_wall = self._wall_due(self._joint_state_period)
            for robot in self.robots.values():
                self.publish_joint_states(robot, now)
        self.camera_stream.publish_due(now)

    def publish_clock(self):
        """Publish the simulation time on /clock."""
        now = self.world.time
        self._next_clock = now + self._clock_period
        self._next_clock_wall = self._wall_due(self._clock_period)
        fill_time_msg(self._clock_msg.clock, now)
        self.clock_pub.publish(self._clock_msg)

    def publish_odometry(self, robot, now):
        """Publish a robot's odometry in its odometry frame (REP 105)."""
        odometry = self.world.odometry(robot.model_name)  # integrates the encoders, always
        if robot.odom_pub.get_subscription_count() == 0:
            return  # nobody would receive it: skip the message, the costly part
        msg = robot.odom_msg
        fill_time_msg(msg.header.stamp, now)
        msg.header.frame_id = odometry.odometry_frame
        msg.child_frame_id = odometry.robot_base_frame
        fill_pose_msg(msg.pose.pose, odometry.position, odometry.orientation)
        fill_twist_msg(msg.twist.twist, odometry.linear_velocity, odometry.angular_velocity)
        robot.odom_pub.publish(msg)

    def publish_joint_states(self, robot, now):
        """Publish the positions and velocities of a robot's moving joints."""
        if robot.joint_states_pub.get_subscription_count() == 0:
            return
        names, positions, velocities = self.world.joint_state(robot.model_name)
        msg = robot.joint_states_msg
        fill_time_msg(msg.header.stamp, now)
        msg.name = names
        msg.position = positions.tolist()
        msg.velocity = velocities.tolist()
        robot.joint_states_pub.publish(msg)

    def cmd_vel_callback(self, model_name, msg):
        """Hand a robot's velocity command to the world; the next steps apply it."""
        try:
            applied = self.world.command_velocity(model_name, msg.linear.x, msg.angular.z)
        except WorldError as error:
            self.get_logger().warning(
                f'ignored cmd_vel for {model_name}: {error}', throttle_duration_sec=1.0)
            return
        if applied != (msg.linear.x, msg.angular.z):
            self.get_logger().warning(
                f'cmd_vel for {model_name} (linear.x {msg.linear.x}, angular.z '
                f'{msg.angular.z}) turns a wheel faster than {MAX_WHEEL_RIM_SPEED} m/s; scaled '
                f'down to linear.x {applied[0]:.4g}, angular.z {applied[1]:.4g}',
                throttle_duration_sec=1.0)

    # --- model services -----------------------------------------------------------------------

    def _spawn_start_up_models(self):
        param = self.get_parameter
        files = list(param('models').value)
        names = list(param('model_names').value) or [
            os.path.splitext(os.path.basename(f))[0] for f in files]
        namespaces = list(param('model_namespaces').value) or [''] * len(files)
        poses = list(param('model_poses').value) or [0.0] * 4 * len(files)
        if not len(files) == len(names) == len(namespaces) == len(poses) // 4:
            raise ValueError('models, model_names, model_namespaces and model_poses '
                             '(4 numbers each) must describe the same number of models')
        for index, (model, name, namespace) in enumerate(zip(files, names, namespaces)):
            x, y, z, yaw = poses[4 * index:4 * index + 4]
            orientation = yaw_quaternion(yaw)
            with open(resolve_model_path(model)) as model_file:
                urdf = model_file.read()
            self.spawn_model(name, urdf, namespace, (x, y, z), orientation, '',
                             base_dir=os.path.dirname(resolve_model_path(model)))

    def spawn_model(self, name, urdf, namespace, position, orientation, reference_frame,
                    base_dir=None):
        """Add a model to the world and give its diff drive, if any, its topics."""
        self.world.spawn_urdf(name, urdf, position=position, orientation=orientation,
                              reference_frame=reference_frame, namespace=namespace,
                              base_dir=base_dir)
        if name in self.world.diff_drive_models():
            try:
                self.robots[name] = RobotTopics(self, name, self.world.namespace(name))
            except Exception:
                self.world.delete_model(name)
                raise
        if self.viewer is not None:
            self._open_viewer()

    def spawn_model_callback(self, request, response):
        """Spawn a URDF model; failures are answered, never raised."""
        def spawn():
            position, orientation = pose_from_msg(request.initial_pose)
            self.spawn_model(request.model_name, request.model_xml, request.robot_namespace,
                             position, orientation, request.reference_frame)
            return f'SpawnModel: Successfully spawned entity {request.model_name!r}'
        return self._answer('SpawnModel', spawn, response)

    def delete_model_callback(self, request, response):
        """Delete a model and its topics."""
        def delete():
            self.world.delete_model(request.model_name)
            robot = self.robots.pop(request.model_name, None)
            if robot is not None:
                robot.destroy()
            if self.viewer is not None:
                self._open_viewer()
            return f'DeleteModel: Successfully deleted model {request.model_name!r}'
        return self._answer('DeleteModel', delete, response)

    def get_model_list_callback(self, request, response):
        """List every model in spawn order."""
        response.model_names = self.world.model_names()
        response.success = True
        response.status_message = 'GetModelList: got properties'
        return response

    def get_model_state_callback(self, request, response):
        """Report a model's pose and twist in the requested frame."""
        def get_state():
            state = self.world.get_model_state(request.model_name, request.reference_frame)
            response.header.stamp = time_msg(self.world.time)
            response.header.frame_id = request.reference_frame or 'world'
            fill_pose_msg(response.pose, state.position, state.orientation)
            fill_twist_msg(response.twist, state.linear_velocity, state.angular_velocity)
            return 'GetModelState: got properties'
        return self._answer('GetModelState', get_state, response)

    def set_model_state_callback(self, request, response):
        """Move a model to a pose and give it a twist."""
        def set_state():
            position, orientation = pose_from_msg(request.pose)
            linear, angular = twist_from_msg(request.twist)
            self.world.set_model_state(
                request.model_name, position=position, orientation=orientation,
                linear_velocity=linear, angular_velocity=angular,
                reference_frame=request.reference_frame)
            return f'SetModelState: set state of {request.model_name!r}'
        return self._answer('SetModelState', set_state, response)

    def _answer(self, service, operation, response):
        """Run a world operation and report its outcome in success and status_message."""
        try:
            response.status_message = operation()
            response.success = True
        except WorldError as error:
            response.success = False
            response.status_message = f'{service}: {error}'
            self.get_logger().warning(response.status_message)
        except Exception as error:  # a bug must not take the world down with it
            response.success = False
            response.status_message = f'{service}: internal error: {error!r}'
            self.get_logger().error(response.status_message)
        return response

    def reset_simulation_callback(self, request, response):
        """Put every model back at its spawn pose and the clock back to zero."""
        self.world.reset_simulation()
        self._after_reset()
        self.get_logger().info('simulation reset: time 0, every model at its spawn pose')
        return response

    def reset_world_callback(self, request, response):
        """Put every model back at its spawn pose; time goes on."""
        self.world.reset_world()
        self._after_reset()
        self.get_logger().info('world reset: every model at its spawn pose')
        return response

    def _after_reset(self):
        self._anchor_real_time()
        self._next_odom = self._next_joint_states = self.world.time
        self._next_odom_wall = self._next_joint_states_wall = 0.0
        self.publish_clock()
        self.publish_due()

    def pause_physics_callback(self, request, response):
        """Stop stepping; services and /clock keep answering."""
        self.world.pause()
        return response

    def unpause_physics_callback(self, request, response):
        """Resume stepping from where it stopped."""
        self.world.unpause()
        self._anchor_real_time()
        return response

    # --- viewer -------------------------------------------------------------------------------

    def _open_viewer(self):
        """(Re)open MuJoCo's passive viewer on the current model; spawns rebuild the model."""
        import mujoco.viewer
        if self.viewer is not None:
            self.viewer.close()
        try:
            self.viewer = mujoco.viewer.launch_passive(self.world.model, self.world.data)
        except Exception as error:  # no display, no OpenGL
            self.viewer = None
            self.get_logger().error(f'gui:=true but the viewer could not open: {error}')

    def _sync_viewer(self):
        if self.viewer.is_running():
            self.viewer.sync()

    def destroy_node(self):
        """Close the viewer along with the node."""
        if self.viewer is not None:
            self.viewer.close()
            self.viewer = None
        self.camera_stream.close()
        return super().destroy_node()


def main(args=None):
    """Run the MuJoCo world until Ctrl-C."""
    return spin_node(MujocoWorld, args=args)


if __name__ == '__main__':
    main()
