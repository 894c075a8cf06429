"""
Turning as an action: turn tinybot in place by an angle, closed-loop on its odometry.

turn_robot (srv_interfaces/action/TurnRobot) turns the robot by the goal's angle at up to the
goal's angular_vel. Where /control_robot_angle publishes a rate for a time and hopes, this
server steers on the robot's odom: each odometry message updates the heading (unwrapped, so
turns beyond half a revolution count right) and sets the next cmd_vel, slowing down near the
target so that the robot stops within angle_tolerance of it. Feedback (angle turned, angle
remaining) goes out at feedback_rate on the node's clock, which follows /clock with
use_sim_time. A cancel stops the robot at once; the goal ends once the robot is at rest, with
the angle it really turned. A goal that arrives during a turn replaces it: the old goal is
aborted with a message and the new one turns from wherever the robot is. Invalid goals are
rejected before they start, with the reason in the log.

A goal is steered on odometry and timed in simulation time, so it ends, aborted with a message
that says why and the robot told to stop, whenever either stops making sense:

- A reset of the simulation puts time back (``simulation time jumped back by 3.21 s (the
  simulation was reset)``): heard from rclpy through a jump callback on the node's clock, or,
  whatever the node's clock, from an odometry stamp earlier than the one before it
  (``odometry time jumped back by ...``). The goal ends at once.
- A robot moved by someone else (/mujoco/set_model_state, a reset of the world): its heading
  or position jumps between two odometry messages by more than its own twist explains over
  their stamps' interval, plus a margin (``the robot was moved: its heading jumped by +1.000
  rad ...``). The angle turned leaves the jump out. Odometry shows such a jump when it follows
  the robot's true pose (odometry_source 1), or when it starts again at its origin (a reset of
  the world). Tinybot's odometry counts its wheels' turns (odometry_source 0), and
  set_model_state moves the body and leaves the wheels as they were: the server cannot see that
  move, and the goal turns the rest of its angle from where the robot was put.
- A robot deleted, or odometry that stops: ``no odometry on /odom for 1.0 s``.

A pause of the physics stops simulation time and odometry's with it: the goal waits, and goes
on once the physics is unpaused. Time that jumps ahead (a big StepSimulation) only lets the
feedback timer and the odometry timeout see the time that passed.
"""

from enum import Enum
import math

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.clock import JumpThreshold
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.task import Future
from service_tutorial.conversions import seconds_of, yaw_of
from service_tutorial.lesson.turning_input import MAX_ANGLE, MAX_ANGULAR_VEL
from service_tutorial.node_main import spin_node
from srv_interfaces.action import TurnRobot

# Below this yaw rate, in rad/s, the robot counts as at rest after it was told to stop.
AT_REST = 0.01
# Longest wait for the robot to come to rest after it was told to stop, in s.
SETTLE_TIMEOUT = 1.0
# How much further than its twist explains the robot may turn (rad) or go (m) between two
# odometry messages before it counts as moved by someone else: well above what a change of
# speed within one odometry period adds, well below any move made on purpose.
MOVE_MARGIN_ANGLE = 0.05
MOVE_MARGIN_DISTANCE = 0.05


class Outcome(Enum):
    """How a goal ended: the ServerGoalHandle method that records it."""

    SUCCEEDED = 'succeed'
    CANCELED = 'canceled'
    ABORTED = 'abort'


class Turn:
    """One accepted goal: where it started, how far it has turned, and how it ends."""

    def __init__(self, goal_handle, started_at):
        self.goal_handle = goal_handle
        self.angle = goal_handle.request.angle
        self.top_speed = goal_handle.request.angular_vel
        self.started_at = started_at
        self.start_heading = None  # unwrapped odometry heading when the turn began, rad
        self.turned = 0.0
        self.ending = None  # (Outcome, reason) once the robot has been told to stop
        self.stopped_at = None
        self.done = Future()  # set to (Outcome, message) when the goal is over

    def message(self, reason):
        """Say how the goal ended, with what was turned."""
        return f'{reason}: turned {self.turned:.4f} rad of {self.angle:.4f} rad'


def double_range(low, high):
    """Return the allowed range of a double parameter, for its ParameterDescriptor."""
    return [FloatingPointRange(from_value=low, to_value=high, step=0.0)]


class RobotTurningActionServer(Node):
    """Serves turn_robot by steering tinybot on its odometry until it faces the new heading."""

    def __init__(self, **kwargs):
        super().__init__('robot_turning_action_server', **kwargs)
        self.declare_parameter('max_angular_vel', MAX_ANGULAR_VEL, ParameterDescriptor(
            description='fastest angular_vel accepted, in rad/s (the lesson allows pi/2)',
            floating_point_range=double_range(0.0, MAX_ANGULAR_VEL)))
        self.declare_parameter('max_angle', MAX_ANGLE, ParameterDescriptor(
            description='largest |angle| accepted, in rad (default: ten turns)',
            floating_point_range=double_range(0.0, MAX_ANGLE)))
        self.declare_parameter('angle_tolerance', 0.002, ParameterDescriptor(
            description='a turn is done once the robot is this close to its target, in rad',
            floating_point_range=double_range(0.0001, 0.1)))
        self.declare_parameter('deceleration', 1.0, ParameterDescriptor(
            description='how gently the robot slows down near the target, in rad/s^2',
            floating_point_range=double_range(0.01, 100.0)))
        self.declare_parameter('response_time', 0.2, ParameterDescriptor(
            description='how long the robot takes to answer a command as seen in odom, in s: '
                        'near the target it slows down early enough for that',
            floating_point_range=double_range(0.0, 2.0)))
        self.declare_parameter('odom_timeout', 1.0, ParameterDescriptor(
            description='a goal is aborted when odom has been silent this long, in s',
            floating_point_range=double_range(0.1, 60.0)))
        self.declare_parameter('feedback_rate', 10.0, ParameterDescriptor(
            description='how often feedback is published during a turn, in Hz',
            read_only=True, floating_point_range=double_range(0.1, 100.0)))

        self.heading = None  # the robot's odometry heading, unwrapped, rad
        self.last_odom = None  # the odometry message before this one
        self.last_odom_at = None
        # After time went back: (stamp beyond which odometry is from before the jump, the time
        # the clock jumped from), both in s, until odometry from after the jump is heard.
        self.stale_odom = None
        self.turn = None  # the goal being carried out
        self.turns_to_execute = {}  # accepted goals whose execute callback has not run yet

        # Everything below shares the node's default, mutually exclusive callback group, so
        # odometry, goals, cancels and feedback never run at the same time and need no locks.
        # The execute callback awaits the end of its turn without holding any group: rclpy
        # runs it as a task of the executor, so the server keeps taking odometry, cancels and
        # newer goals meanwhile.
        self.cmd_vel_pub = self.create_publisher(Twist, 'cmd_vel', 10)
        # Only the newest odometry matters: a slow turn of the executor skips stale ones.
        self.odom_sub = self.create_subscription(Odometry, 'odom', self.odom_callback, 1)
        self.turn_robot_server = ActionServer(
            self, TurnRobot, 'turn_robot', self.execute_callback,
            goal_callback=self.goal_callback,
            handle_accepted_callback=self.handle_accepted_callback,
            cancel_callback=self.cancel_callback)
        # On the node's clock, so with use_sim_time it follows /clock; idle between turns.
        self.feedback_timer = self.create_timer(
            1.0 / self.get_parameter('feedback_rate').value, self.feedback_callback,
            autostart=False)
        # Time going back ends the goal under way (see the module's docstring). rclpy calls
        # time_jumped from its TimeSource's /clock subscription, right after the new time is
        # set: an executor callback in the default group, so it never runs beside the others.
        # The handle is kept: dropping it would remove the callback.
        self.time_jump_handle = self.get_clock().create_jump_callback(
            JumpThreshold(min_forward=None, min_backward=Duration(nanoseconds=-1),
                          on_clock_change=False),
            post_callback=self.time_jumped)
        self.get_logger().info('==== Robot Turning Action Server Started ====')

    # --- goals ---------------------------------------------------------------------------------

    def goal_callback(self, goal):
        """Accept a goal that can be carried out; reject any other, saying why."""
        refusal = self.refusal(goal)
        if refusal is not None:
            self.get_logger().warning(f'rejected goal: {refusal}')
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def refusal(self, goal):
        """Return why a goal cannot be carried out, or None if it can."""
        max_angular_vel = self.get_parameter('max_angular_vel').value
        max_angle = self.get_parameter('max_angle').value
        for name in ('angle', 'angular_vel'):
            value = getattr(goal, name)
            if not math.isfinite(value):
                return f'{name} {value} is not a finite number'
        if not goal.angular_vel > 0.0:
            return (f'angular_vel {goal.angular_vel} rad/s must be above 0 '
                    '(the sign of angle gives the direction)')
        if goal.angular_vel > max_angular_vel:
            return (f'angular_vel {goal.angular_vel} rad/s is faster than '
                    f'max_angular_vel {max_angular_vel} rad/s')
        if abs(goal.angle) > max_angle:
            return f'angle {goal.angle} rad is beyond max_angle {max_angle:.4f} rad either way'
        return None

    def handle_accepted_callback(self, goal_handle):
        """Start the new goal at once; a goal still under way gives way to it."""
        turn = Turn(goal_handle, self.get_clock().now())
        previous = self.turn
        if previous is not None:
            # The new goal takes over the robot as it is: no stop in between.
            outcome, reason = previous.ending or (Outcome.ABORTED, 'replaced by a newer goal')
            self.finish(previous, outcome, reason)
        self.turn = turn
        self.turns_to_execute[bytes(goal_handle.goal_id.uuid)] = turn
        self.get_logger().info(
            f'turning {turn.angle:.4f} rad at up to {turn.top_speed} rad/s')
        self.begin(turn)
        self.feedback_timer.reset()
        goal_handle.execute()

    async def execute_callback(self, goal_handle):
        """Wait for the goal's turn to end; record how it ended and return its result."""
        turn = self.turns_to_execute.pop(bytes(goal_handle.goal_id.uuid))
        outcome, message = await turn.done
        getattr(goal_handle, outcome.value)()
        return TurnRobot.Result(success=outcome is Outcome.SUCCEEDED,
                                angle_turned=turn.turned, message=message)

    def cancel_callback(self, goal_handle):
        """Stop the robot at once for a cancel of the goal under way; refuse any other."""
        turn = self.turn
        if turn is None or turn.goal_handle != goal_handle or turn.ending is not None:
            return CancelResponse.REJECT
        self.stop(turn, Outcome.CANCELED, 'canceled')
        return CancelResponse.ACCEPT

    # --- the turn ------------------------------------------------------------------------------

    def odom_callback(self, msg):
        """Follow the robot's heading and steer (or settle) the turn under way."""
        if self.stale_odom is not None:
            newest_fresh, jumped_from = self.stale_odom
            if seconds_of(msg.header.stamp) > newest_fresh and \
                    self.get_clock().now().nanoseconds / 1e9 < jumped_from:
                # Sent before time went back, heard after: closer to the old time than to the
                # new one. Following it would make the next, fresh message look like a jump.
                return
            self.stale_odom = None
        last, self.last_odom = self.last_odom, msg
        yaw = yaw_of(msg.pose.pose.orientation)
        turning = yaw if last is None else math.remainder(
            yaw - yaw_of(last.pose.pose.orientation), math.tau)
        self.heading = turning if self.heading is None else self.heading + turning
        self.last_odom_at = self.get_clock().now()
        turn = self.turn
        if turn is None:
            return
        if turn.start_heading is None:
            self.begin(turn)
        elif turn.ending is None and last is not None:
            interruption = self.interruption(last, msg, turning)
            if interruption is not None:
                # The jump is not the robot's turning: leave it out of the angle turned.
                turn.start_heading += turning
                turn.turned = self.heading - turn.start_heading
                self.stop(turn, Outcome.ABORTED, interruption)
                self.finish(turn, *turn.ending)
                return
        turn.turned = self.heading - turn.start_heading
        if turn.ending is None:
            self.steer(turn)
        elif abs(msg.twist.twist.angular.z) < AT_REST:
            self.finish(turn, *turn.ending)

    @staticmethod
    def interruption(last, msg, turning):
        """Say why odometry cannot be followed from last to msg (turning apart), or None."""
        interval = seconds_of(msg.header.stamp) - seconds_of(last.header.stamp)
        if interval < 0.0:
            return (f'odometry time jumped back by {-interval:.2f} s '
                    '(the simulation was reset)')
        rate = max(abs(last.twist.twist.angular.z), abs(msg.twist.twist.angular.z))
        explained = rate * interval + MOVE_MARGIN_ANGLE
        if abs(turning) > explained:
            return (f'the robot was moved: its heading jumped by {turning:+.3f} rad in '
                    f'{interval:.3f} s of odometry, where its turning explains at most '
                    f'{explained:.3f} rad')
        before, after = last.pose.pose.position, msg.pose.pose.position
        shift = math.hypot(after.x - before.x, after.y - before.y)
        speed = max(math.hypot(twist.linear.x, twist.linear.y)
                    for twist in (last.twist.twist, msg.twist.twist))
        explained = speed * interval + MOVE_MARGIN_DISTANCE
        if shift > explained:
            return (f'the robot was moved: its position jumped by {shift:.3f} m in '
                    f'{interval:.3f} s of odometry, where its speed explains at most '
                    f'{explained:.3f} m')
        return None

    def time_jumped(self, jump):
        """End the goal under way when simulation time went back; forget older odometry."""
        if jump.delta.nanoseconds >= 0:
            return
        # What odometry said before the jump belongs to another time: follow it afresh, and
        # leave out a message from before the jump that is still on its way.
        self.heading = self.last_odom = self.last_odom_at = None
        now = self.get_clock().now().nanoseconds / 1e9
        jumped_from = now - jump.delta.nanoseconds / 1e9
        self.stale_odom = ((now + jumped_from) / 2.0, jumped_from)
        turn = self.turn
        if turn is None:
            return
        self.stop(turn, Outcome.ABORTED, f'simulation time jumped back by '
                                         f'{-jump.delta.nanoseconds / 1e9:.2f} s '
                                         '(the simulation was reset)')
        self.finish(turn, *turn.ending)

    def begin(self, turn):
        """Take the heading the turn starts from, once odometry has given one."""
        if self.heading is not None:
            turn.start_heading = self.heading

    def steer(self, turn):
        """Command the speed that brings the robot to its target without overshooting."""
        remaining = turn.angle - turn.turned
        if abs(remaining) <= self.get_parameter('angle_tolerance').value:
            self.stop(turn, Outcome.SUCCEEDED, 'reached the goal')
            return
        deceleration = self.get_parameter('deceleration').value
        response_time = self.get_parameter('response_time').value
        # The fastest speed from which the robot still stops in the angle left, although it
        # goes on for response_time before it slows down at the chosen deceleration:
        # remaining = speed * response_time + speed**2 / (2 * deceleration).
        stopping_speed = deceleration * (
            math.sqrt(response_time**2 + 2.0 * abs(remaining) / deceleration) - response_time)
        speed = min(turn.top_speed, stopping_speed)
        command = Twist()
        command.angular.z = math.copysign(speed, remaining)
        self.cmd_vel_pub.publish(command)

    def stop(self, turn, outcome, reason):
        """Tell the robot to stop; the goal ends with outcome once it is at rest."""
        self.cmd_vel_pub.publish(Twist())
        turn.ending = (outcome, reason)
        turn.stopped_at = self.get_clock().now()

    def finish(self, turn, outcome, reason):
        """End a goal: its execute callback records the outcome and returns the result."""
        message = turn.message(reason)
        if outcome is Outcome.ABORTED:
            self.get_logger().warning(message)
        else:
            self.get_logger().info(message)
        turn.done.set_result((outcome, message))
        if self.turn is turn:
            self.turn = None
            self.feedback_timer.cancel()

    def feedback_callback(self):
        """Report progress; end a turn whose odometry went silent or that never settles."""
        turn = self.turn
        if turn is None:
            self.feedback_timer.cancel()
            return
        now = self.get_clock().now()
        odom_timeout = self.get_parameter('odom_timeout').value
        last_heard = turn.started_at if self.last_odom_at is None else max(
            turn.started_at, self.last_odom_at)
        if now - last_heard > Duration(seconds=odom_timeout):
            self.stop(turn, Outcome.ABORTED, f'no odometry on {self.odom_sub.topic_name} '
                                             f'for {odom_timeout} s')
            self.finish(turn, *turn.ending)
        elif turn.ending is not None:
            if now - turn.stopped_at > Duration(seconds=SETTLE_TIMEOUT):
                self.finish(turn, *turn.ending)
        else:
            turn.goal_handle.publish_feedback(TurnRobot.Feedback(
                angle_turned=turn.turned, angle_remaining=turn.angle - turn.turned))

    def destroy_node(self):
        """Stop the robot if the node goes away in the middle of a turn."""
        if self.turn is not None and self.context.ok():
            self.cmd_vel_pub.publish(Twist())
        self.time_jump_handle.unregister()
        self.turn_robot_server.destroy()
        return super().destroy_node()


def main(args=None):
    """Run the turning action server until Ctrl-C."""
    return spin_node(RobotTurningActionServer, args=args)


if __name__ == '__main__':
    main()
