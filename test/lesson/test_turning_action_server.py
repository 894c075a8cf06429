"""The turning action server through turn_robot, turning tinybot in a world the test steps."""

import math
import os
import pathlib
import re

from action_msgs.msg import GoalStatus
from action_msgs.srv import CancelGoal
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from programs import program_path
import pytest
from rcl_interfaces.srv import DescribeParameters
from rclpy.clock import ClockChange, TimeJump
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from service_tutorial.conversions import make_pose, seconds_of, time_msg, yaw_of
from service_tutorial.lesson.goal_client import GoalClient
from service_tutorial.lesson.model_services import model_path
from service_tutorial.lesson.robot_turning_action_server import RobotTurningActionServer
from service_tutorial.testing.simulated_world import SimulatedWorld
from srv_interfaces.action import TurnRobot

pytestmark = pytest.mark.ros

# Steps taken at a time: tinybot's odometry period (20 ms), so that the server steers on every
# odometry message, as it does in real time.
CHUNK = 10
# The most simulation time a test waits for tinybot to do what it should, in s.
TURN_LIMIT = 60.0


class SteppedActionWorld:
    """A paused world, the action server on its simulation time and a client; the test steps."""

    def __init__(self, world_parameters=None, **server_parameters):
        self.world = SimulatedWorld(**(world_parameters or {}))
        try:
            context = self.world.context
            overrides = [Parameter('use_sim_time', value=True)]
            overrides += [Parameter(name, value=value)
                          for name, value in server_parameters.items()]
            self.server = self.world.add_node(
                RobotTurningActionServer(context=context, parameter_overrides=overrides))
            user = self.world.add_node(Node('turning_test', context=context))
            self.cmd_vel = []
            user.create_subscription(Twist, '/cmd_vel', self.cmd_vel.append, 100)
            self.action_client = GoalClient(user, TurnRobot, '/turn_robot')
            assert self.action_client.wait_for_server(timeout_sec=10.0)
        except BaseException:
            self.world.close()
            raise

    def close(self):
        self.action_client.destroy()
        self.world.close()

    def state(self):
        """Tinybot's ground truth: pose and twist in the world."""
        return self.world.entity_state('tinybot')

    def step_until(self, predicate, *, limit=TURN_LIMIT, each=lambda: None):
        """Step CHUNK steps at a time, each() after each, until predicate(); False past limit."""
        end = self.world.time + limit
        while not predicate():
            if self.world.time >= end:
                return False
            self.world.step(CHUNK)
            each()
        return True

    def step_for(self, seconds):
        self.world.step(round(seconds / self.world.timestep))

    def turn(self, angle, angular_vel):
        """Turn by the action; return its status, result, feedback and the ground truth turn."""
        truth = GroundTruth(self)
        truth.wait_at_rest()
        truth.turned = 0.0
        start = truth.time
        goal = Goal(self, angle, angular_vel)
        assert goal.handle.accepted
        assert truth.follow_until(goal.done)
        self.turn_duration = truth.time - start  # simulation time from goal to result
        truth.wait_at_rest()
        status, result = goal.result()
        return status, result, goal.feedback, truth.turned


class GroundTruth:
    """Tinybot's heading from its state, sampled after each chunk of steps and unwrapped."""

    def __init__(self, action_world):
        self.action_world = action_world
        self.samples = []  # (simulation time, yaw rate) of every sample taken
        state = action_world.state()
        self.last = yaw_of(state.pose.orientation)
        self.turned = 0.0
        self.time = seconds_of(state.header.stamp)
        self.yaw_rate = state.twist.angular.z

    def sample(self):
        """Read the state once more; return it."""
        state = self.action_world.state()
        heading = yaw_of(state.pose.orientation)
        self.turned += math.remainder(heading - self.last, math.tau)
        self.last = heading
        self.time = seconds_of(state.header.stamp)
        self.yaw_rate = state.twist.angular.z
        self.samples.append((self.time, self.yaw_rate))
        return state

    def follow_until(self, predicate, *, limit=TURN_LIMIT):
        """Step and sample until predicate() holds; return whether it came to hold in time."""
        return self.action_world.step_until(predicate, limit=limit, each=self.sample)

    def wait_at_rest(self):
        self.sample()
        assert self.follow_until(lambda: abs(self.yaw_rate) < 1e-3), 'tinybot did not stop'

    def follow_for(self, duration):
        """Follow tinybot until `duration` more seconds of simulation time have passed."""
        self.sample()
        end = self.time + duration
        assert self.follow_until(lambda: self.time >= end)


class Goal:
    """One goal sent through the test's action client, with the feedback it received."""

    def __init__(self, action_world, angle, angular_vel):
        self.action_world = action_world
        self.feedback = []
        future = action_world.action_client.send_goal_async(
            TurnRobot.Goal(angle=angle, angular_vel=angular_vel),
            feedback_callback=lambda msg: self.feedback.append(msg.feedback))
        assert action_world.world.wait_for(future.done), 'no answer to the goal'
        self.handle = future.result()
        self.result_future = self.handle.get_result_async() if self.handle.accepted else None

    def done(self):
        return self.result_future.done()

    def result(self):
        """Return the goal's status and result, stepping until they come if need be."""
        assert self.action_world.step_until(self.done), 'no result'
        response = self.result_future.result()
        return response.status, response.result


@pytest.fixture
def action_world():
    stepped = SteppedActionWorld()
    yield stepped
    stepped.close()


def test_a_quarter_turn_left_ends_on_target_with_rising_feedback(action_world):
    status, result, feedback, turned = action_world.turn(math.pi / 2, 0.5)
    print(f'\npi/2 at 0.5 rad/s: turned {turned:.4f} rad by ground truth '
          f'({100.0 * (turned / (math.pi / 2) - 1.0):+.2f} %), result {result.angle_turned:.4f}')

    assert status == GoalStatus.STATUS_SUCCEEDED
    assert result.success
    assert turned == pytest.approx(math.pi / 2, rel=0.01)
    # Stopped within 0.01 rad of the target by the robot's own odometry, close to the truth.
    assert result.angle_turned == pytest.approx(math.pi / 2, abs=0.01)
    assert result.angle_turned == pytest.approx(turned, abs=0.02)
    assert result.message.startswith('reached the goal')
    # Feedback at 10 Hz of simulation time for as long as the turn took; the angle only grows.
    print(f'\n{len(feedback)} feedback messages over {action_world.turn_duration:.2f} s')
    assert len(feedback) >= 5
    assert len(feedback) == pytest.approx(10.0 * action_world.turn_duration, abs=2.0)
    progress = [report.angle_turned for report in feedback]
    assert all(later >= earlier - 1e-3 for earlier, later in zip(progress, progress[1:]))
    assert progress[-1] > progress[0] + 1.0
    for report in feedback:
        assert report.angle_remaining == pytest.approx(math.pi / 2 - report.angle_turned)
    # The ramp down: the last commands before the stop are slower than the top speed.
    commands = [msg.angular.z for msg in action_world.cmd_vel]
    assert max(commands) == pytest.approx(0.5)
    assert commands[-1] == 0.0 and 0.0 < commands[-2] < 0.2


def test_one_and_a_half_turns_clockwise_are_counted_unwrapped(action_world):
    status, result, feedback, turned = action_world.turn(-3 * math.pi, 1.5)
    print(f'\n-3 pi at 1.5 rad/s: turned {turned:.4f} rad by ground truth '
          f'({100.0 * (turned / (-3 * math.pi) - 1.0):+.2f} %), {len(feedback)} feedback messages')

    assert status == GoalStatus.STATUS_SUCCEEDED
    assert result.success
    assert turned == pytest.approx(-3 * math.pi, rel=0.01)
    assert result.angle_turned == pytest.approx(-3 * math.pi, abs=0.01)
    progress = [-report.angle_turned for report in feedback]
    assert len(progress) >= 5
    assert all(later >= earlier - 1e-3 for earlier, later in zip(progress, progress[1:]))
    assert progress[-1] > math.pi  # past half a revolution, still counting


def test_a_cancel_stops_tinybot_at_once_and_returns_what_was_turned(action_world):
    server = action_world.server
    canceled_at = []

    def cancel_callback(goal_handle):
        canceled_at.append(seconds_of(server.get_clock().now().to_msg()))
        return server.cancel_callback(goal_handle)

    server.turn_robot_server.register_cancel_callback(cancel_callback)
    truth = GroundTruth(action_world)
    truth.wait_at_rest()
    truth.turned = 0.0
    goal = Goal(action_world, 2.0, 0.5)
    truth.follow_for(1.0)
    assert truth.yaw_rate == pytest.approx(0.5, abs=0.05), 'not turning at full speed yet'

    cancel = goal.handle.cancel_goal_async()
    assert action_world.world.wait_for(cancel.done)
    assert cancel.result().return_code == CancelGoal.Response.ERROR_NONE
    (accepted_at,) = canceled_at
    first_sample = len(truth.samples)
    assert truth.follow_until(lambda: truth.time >= accepted_at + 0.5)
    truth.wait_at_rest()
    status, result = goal.result()

    after = [(time, rate) for time, rate in truth.samples[first_sample:]
             if time >= accepted_at + 0.2]
    assert after and after[0][0] <= accepted_at + 0.5
    print(f'\ncancel: largest yaw rate from 0.2 s after it '
          f'{max(abs(rate) for _, rate in after):.4f} rad/s; result {result.angle_turned:.4f} '
          f'rad, ground truth {truth.turned:.4f} rad')
    assert all(abs(rate) < 0.05 for _, rate in after), after
    assert status == GoalStatus.STATUS_CANCELED
    assert not result.success
    assert result.message.startswith('canceled')
    assert 0.3 < result.angle_turned < 1.0
    assert result.angle_turned == pytest.approx(truth.turned, abs=0.02)


def test_a_second_goal_replaces_the_first(action_world):
    truth = GroundTruth(action_world)
    truth.wait_at_rest()
    truth.turned = 0.0
    first = Goal(action_world, 3.0, 0.5)
    assert truth.follow_until(
        lambda: first.feedback and first.feedback[-1].angle_turned > 0.3)

    second = Goal(action_world, -1.0, 1.0)
    assert second.handle.accepted
    first_status, first_result = first.result()
    assert truth.follow_until(second.done)
    truth.wait_at_rest()
    second_status, second_result = second.result()

    assert first_status == GoalStatus.STATUS_ABORTED
    assert not first_result.success
    assert first_result.message.startswith('replaced by a newer goal')
    assert 0.3 < first_result.angle_turned < 3.0
    assert second_status == GoalStatus.STATUS_SUCCEEDED
    assert second_result.angle_turned == pytest.approx(-1.0, abs=0.01)
    assert truth.turned == pytest.approx(first_result.angle_turned - 1.0, abs=0.03)


@pytest.mark.parametrize('angle, angular_vel, reason', [
    (math.nan, 0.5, 'angle nan is not a finite number'),
    (math.inf, 0.5, 'angle inf is not a finite number'),
    (1.0, math.nan, 'angular_vel nan is not a finite number'),
    (1.0, 0.0, 'angular_vel 0.0 rad/s must be above 0'),
    (1.0, -1.0, 'angular_vel -1.0 rad/s must be above 0'),
    (1.0, 2.0, 'angular_vel 2.0 rad/s is faster than max_angular_vel 1.5707 rad/s'),
    (1000.0, 0.5, 'angle 1000.0 rad is beyond max_angle 62.8319 rad'),
], ids=['nan-angle', 'infinite-angle', 'nan-velocity', 'zero-velocity', 'negative-velocity',
        'too-fast', 'too-far'])
def test_bad_goals_are_rejected_and_tinybot_stays_still(
        action_world, capfd, angle, angular_vel, reason):
    truth = GroundTruth(action_world)
    truth.wait_at_rest()
    before = truth.last

    goal = Goal(action_world, angle, angular_vel)
    truth.follow_for(0.5)

    assert not goal.handle.accepted
    assert action_world.cmd_vel == []
    assert truth.last == pytest.approx(before, abs=1e-4)
    assert f'rejected goal: {reason}' in capfd.readouterr().err


def test_the_limits_are_inclusive_and_a_zero_turn_succeeds_at_once(action_world):
    status, result, feedback, turned = action_world.turn(0.0, 1.5707)

    assert status == GoalStatus.STATUS_SUCCEEDED
    assert result.angle_turned == pytest.approx(0.0, abs=1e-3)
    assert turned == pytest.approx(0.0, abs=1e-3)
    assert all(msg.angular.z == 0.0 for msg in action_world.cmd_vel)
    ten_turns_right = Goal(action_world, -20 * math.pi, 1.5707)
    assert ten_turns_right.handle.accepted
    ten_turns_right.handle.cancel_goal_async()
    status, result = ten_turns_right.result()
    assert status == GoalStatus.STATUS_CANCELED


def test_parameters_are_described_and_held_to_their_ranges(ros):
    ros.add_node(RobotTurningActionServer())
    names = ['max_angular_vel', 'max_angle', 'angle_tolerance', 'deceleration', 'response_time',
             'odom_timeout', 'feedback_rate']

    described = ros.call(DescribeParameters, '/robot_turning_action_server/describe_parameters',
                         DescribeParameters.Request(names=names)).descriptors

    assert all(descriptor.description for descriptor in described)
    read_only = {descriptor.name for descriptor in described if descriptor.read_only}
    assert read_only == {'feedback_rate'}
    ranges = {descriptor.name: descriptor.floating_point_range[0] for descriptor in described}
    assert ranges['max_angular_vel'].to_value == pytest.approx(1.5707)
    server = 'robot_turning_action_server'
    assert not ros.set_parameter(server, 'max_angular_vel', 2.0).successful
    assert not ros.set_parameter(server, 'feedback_rate', 20.0).successful
    assert ros.set_parameter(server, 'max_angular_vel', 1.0).successful


def test_a_goal_without_odometry_is_aborted_with_the_reason(ros):
    ros.add_node(RobotTurningActionServer(
        parameter_overrides=[Parameter('odom_timeout', value=0.2)]))
    action_client = ros.action_client(TurnRobot, '/turn_robot')
    assert action_client.wait_for_server(timeout_sec=10.0)
    future = action_client.send_goal_async(TurnRobot.Goal(angle=1.0, angular_vel=0.5))
    assert ros.wait_for(future.done)
    result_future = future.result().get_result_async()
    assert ros.wait_for(result_future.done)

    response = result_future.result()
    assert response.status == GoalStatus.STATUS_ABORTED
    assert response.result.message.startswith('no odometry on /odom for 0.2 s')
    assert response.result.angle_turned == 0.0


def test_both_programs_are_executables_of_the_package():
    # What `ros2 pkg executables service_tutorial` lists: the executable files in lib/<package>.
    directory = os.path.dirname(program_path('robot_turning_action_server'))
    executables = {name for name in os.listdir(directory)
                   if os.access(os.path.join(directory, name), os.X_OK)}
    assert {'robot_turning_action_server', 'robot_turning_action_client'} <= executables


def turning_at_full_speed(action_world, angle, angular_vel):
    """Send a goal and follow tinybot until it turns at full speed; return goal and truth."""
    truth = GroundTruth(action_world)
    truth.wait_at_rest()
    truth.turned = 0.0
    goal = Goal(action_world, angle, angular_vel)
    assert goal.handle.accepted
    assert truth.follow_until(lambda: abs(truth.yaw_rate) > 0.9 * angular_vel)
    truth.follow_for(0.5)
    assert not goal.done()
    return goal, truth


def told_to_stop_and_still(action_world):
    """Check that the last command was a stop and tinybot is still half a second later."""
    assert action_world.world.wait_for(lambda: action_world.cmd_vel[-1] == Twist())
    told_to_stop = len(action_world.cmd_vel)
    action_world.step_for(0.5)
    assert abs(action_world.state().twist.angular.z) < 1e-3
    assert all(msg == Twist() for msg in action_world.cmd_vel[told_to_stop:])


def test_a_reset_during_a_goal_aborts_it_at_once_and_the_next_goal_succeeds(action_world):
    goal, _ = turning_at_full_speed(action_world, 3.0, 0.5)

    action_world.world.reset()

    # At once: without a step after the world's answer to the reset.
    assert action_world.world.wait_for(goal.done), 'no result before the next step'
    status, result = goal.result()
    print(f'\nreset: {result.message}')
    assert status == GoalStatus.STATUS_ABORTED
    assert not result.success
    assert 'time jumped back by' in result.message
    assert '(the simulation was reset)' in result.message
    assert 0.1 < result.angle_turned < 3.0
    told_to_stop_and_still(action_world)
    status, result, _, turned = action_world.turn(1.0, 0.5)
    assert status == GoalStatus.STATUS_SUCCEEDED
    assert result.angle_turned == pytest.approx(1.0, abs=0.01)
    assert turned == pytest.approx(1.0, rel=0.02)


@pytest.fixture
def world_odometry_world(tmp_path):
    """Tinybot with odometry from the simulator's ground truth, which a move shows."""
    urdf = pathlib.Path(model_path('tinybot.urdf')).read_text()
    encoder = '<odometry_source>0</odometry_source>'
    assert encoder in urdf
    path = tmp_path / 'tinybot_world_odometry.urdf'
    path.write_text(urdf.replace(encoder, '<odometry_source>1</odometry_source>'))
    stepped = SteppedActionWorld(world_parameters={
        'models': [str(path)], 'model_names': ['tinybot'], 'model_namespaces': ['']})
    yield stepped
    stepped.close()


@pytest.mark.parametrize('yaw_change, shift, jump', [
    (1.0, 0.0, r'its heading jumped by \+(\S+) rad'),
    (0.0, 1.0, r'its position jumped by (\S+) m'),
], ids=['turned', 'shifted'])
def test_a_robot_moved_during_a_goal_ends_it_and_is_told_to_stop(
        world_odometry_world, yaw_change, shift, jump):
    action_world = world_odometry_world
    goal, truth = turning_at_full_speed(action_world, 3.0, 0.5)
    state = action_world.state()
    position, yaw = state.pose.position, yaw_of(state.pose.orientation) + yaw_change
    moved_to = make_pose(position.x + shift, position.y, position.z,
                         quaternion=(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)))

    action_world.world.set_entity_state('tinybot', moved_to)

    assert truth.follow_until(goal.done, limit=10.0)
    status, result = goal.result()
    print(f'\nmoved: {result.message}')
    assert status == GoalStatus.STATUS_ABORTED
    assert not result.success
    named = re.match(f'the robot was moved: {jump}', result.message)
    assert named, result.message
    assert float(named.group(1)) == pytest.approx(yaw_change + shift, abs=0.05)
    # What the robot turned itself, the jump left out.
    assert 0.1 < result.angle_turned < 1.0
    told_to_stop_and_still(action_world)
    status, result, _, turned = action_world.turn(-1.0, 0.5)
    assert status == GoalStatus.STATUS_SUCCEEDED
    assert turned == pytest.approx(-1.0, rel=0.02)


def test_a_tinybot_moved_during_a_goal_turns_the_rest_from_where_it_was_put(action_world):
    # Tinybot's odometry counts its wheels' turns, which a move leaves as they were: the
    # server cannot see it, and the goal ends as any other, neither hanging nor spinning.
    goal, truth = turning_at_full_speed(action_world, 2.0, 0.5)
    state = action_world.state()
    yaw = yaw_of(state.pose.orientation) + 1.0
    moved_to = make_pose(state.pose.position.x, state.pose.position.y, state.pose.position.z,
                         quaternion=(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)))

    action_world.world.set_entity_state('tinybot', moved_to)

    assert truth.follow_until(goal.done)
    truth.wait_at_rest()
    status, result = goal.result()
    print(f'\nmoved tinybot: {result.message}; ground truth {truth.turned:.4f} rad')
    assert status == GoalStatus.STATUS_SUCCEEDED
    assert result.angle_turned == pytest.approx(2.0, abs=0.01)
    assert truth.turned == pytest.approx(3.0, abs=0.2)
    told_to_stop_and_still(action_world)


def test_a_robot_deleted_during_a_goal_ends_it_once_odometry_has_been_silent(action_world):
    goal, _ = turning_at_full_speed(action_world, 3.0, 0.5)
    world = action_world.world

    world.delete_entity('tinybot')
    deleted_at = world.time

    status, result = goal.result()
    assert status == GoalStatus.STATUS_ABORTED
    assert result.message.startswith('no odometry on /odom for 1.0 s')
    # Ended by simulation time, one odom_timeout after the last odometry (the upper bound only
    # leaves room for the result's way back on a busy machine).
    assert deleted_at + 0.9 < world.time < deleted_at + 2.0
    # The stop comes on /cmd_vel, which the result does not wait for.
    assert world.wait_for(lambda: action_world.cmd_vel[-1] == Twist())


def odometry(stamp, yaw):
    """Return an odometry message of tinybot at rest at the origin, facing yaw."""
    msg = Odometry()
    msg.header.stamp = time_msg(stamp)
    msg.pose.pose = make_pose(0.0, 0.0, 0.0,
                              quaternion=(0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)))
    return msg


def test_odometry_sent_before_time_went_back_and_heard_after_is_left_out(rclpy_session):
    # The order a busy executor may hand them over in: odometry, the jump back (from /clock),
    # odometry the world sent before its reset, then odometry from after it.
    server = RobotTurningActionServer(
        parameter_overrides=[Parameter('use_sim_time', value=True)])
    try:
        server.odom_callback(odometry(5.00, 0.3))
        server.time_jumped(TimeJump(ClockChange.ROS_TIME_NO_CHANGE, Duration(seconds=-5.0)))
        server.odom_callback(odometry(5.02, 0.31))
        assert server.heading is None and server.last_odom is None

        server.odom_callback(odometry(0.02, 0.0))
        server.odom_callback(odometry(0.04, 0.01))

        assert server.heading == pytest.approx(0.01)
        assert seconds_of(server.last_odom.header.stamp) == pytest.approx(0.04)
    finally:
        server.destroy_node()
