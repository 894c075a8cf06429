"""
The lesson's turning service: turn tinybot at a given rate for a given time.

/control_robot_angle (srv_interfaces/srv/ControlTurningMessage) publishes angular_vel on
cmd_vel for time_duration seconds of ROS time (simulation time with use_sim_time), then a
zero Twist, and answers success. Unlike the ROS 1 original, which busy-looped inside its
callback, the node never blocks its executor: the service callback is a coroutine that queues
the turn and awaits its end, while two timers carry the turn out. On simulation time a turn
starts with the next /clock message, as it stops with one, so that the world sees both at the
same point of its stepping. Requests that arrive during a turn wait for the turns before them
(first come, first served). A zero-length turn stops the robot and succeeds at once when its
turn comes.
"""

from collections import deque
import math

from geometry_msgs.msg import Twist
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.clock import JumpThreshold
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.task import Future
from service_tutorial.lesson.turning_input import MAX_ANGULAR_VEL
from service_tutorial.node_main import spin_node
from srv_interfaces.srv import ControlTurningMessage


class Turn:
    """One accepted request: its command, when it started, and the future its caller awaits."""

    def __init__(self, time_duration, angular_vel):
        self.time_duration = time_duration
        self.command = Twist()
        self.command.angular.z = angular_vel
        self.start = None
        self.ticks_without_listener = 0
        self.done = Future()


class RobotTurningServer(Node):
    """Serves /control_robot_angle by publishing cmd_vel for the requested time."""

    def __init__(self, **kwargs):
        super().__init__('robot_turning_server', **kwargs)
        self.declare_parameter('publish_rate', 20.0, ParameterDescriptor(
            description='how often cmd_vel is repeated during a turn, in Hz', read_only=True))
        self.declare_parameter('max_angular_vel', MAX_ANGULAR_VEL, ParameterDescriptor(
            description='fastest turn accepted, in rad/s (either direction)'))
        self.declare_parameter('max_duration', 60, ParameterDescriptor(
            description='longest turn accepted, in seconds'))
        self.publish_rate = self.get_parameter('publish_rate').value
        if not self.publish_rate > 0.0:
            raise ValueError(f'publish_rate must be above 0 Hz, got {self.publish_rate}')

        self.turns = deque()
        self.cmd_vel_pub = self.create_publisher(Twist, 'cmd_vel', 10)
        # Reentrant: while one request's coroutine awaits the end of its turn, the executor
        # must be free to take the next request and queue it.
        self.turning_srv = self.create_service(
            ControlTurningMessage, 'control_robot_angle', self.control_robot_angle_callback,
            callback_group=ReentrantCallbackGroup())
        # Both timers run on the node's clock, so on simulation time they follow /clock.
        # They idle (cancelled) until a turn starts.
        self.publish_timer = self.create_timer(
            1.0 / self.publish_rate, self.publish_callback, autostart=False)
        self.stop_timer = self.create_timer(1.0, self.stop_callback, autostart=False)
        # Each new simulation time starts a turn waiting for it, and time going back ends the
        # turn under way (time_moved). rclpy calls it from its TimeSource's /clock
        # subscription, right after the new time is set: an executor callback in this node's
        # default group, the timers' group, so it never runs beside them. The handle is kept:
        # dropping it would remove the callback.
        self.time_jump_handle = self.get_clock().create_jump_callback(
            JumpThreshold(min_forward=Duration(nanoseconds=1),
                          min_backward=Duration(nanoseconds=-1), on_clock_change=False),
            post_callback=self.time_moved)
        self.get_logger().info('==== Robot Turning Server Started ====')

    async def control_robot_angle_callback(self, request, response):
        """Queue a valid turn and answer once it is done; refuse an invalid one at once."""
        refusal = self.refusal(request)
        if refusal is not None:
            self.get_logger().warning(f'refused: {refusal}')
            response.success = False
            return response
        turn = Turn(request.time_duration, request.angular_vel)
        self.turns.append(turn)
        if len(self.turns) == 1:
            self.start_turn(turn)
        else:
            self.get_logger().info(
                f'queued {request.angular_vel} rad/s for {request.time_duration} s '
                f'behind {len(self.turns) - 1} turn(s)')
        response.success = await turn.done
        return response

    def refusal(self, request):
        """Return why a request cannot be carried out, or None if it can."""
        max_angular_vel = self.get_parameter('max_angular_vel').value
        max_duration = self.get_parameter('max_duration').value
        if not math.isfinite(request.angular_vel):
            return f'angular_vel {request.angular_vel} is not a finite number'
        if abs(request.angular_vel) > max_angular_vel:
            return (f'angular_vel {request.angular_vel} rad/s is faster than '
                    f'max_angular_vel {max_angular_vel} rad/s')
        if request.time_duration > max_duration:
            return (f'time_duration {request.time_duration} s is longer than '
                    f'max_duration {max_duration} s')
        return None

    def start_turn(self, turn):
        """Start the turn now, or on simulation time with the next /clock (time_moved)."""
        if turn.time_duration == 0:
            self.finish_turn()
            return
        self.publish_timer.reset()
        if not self.get_clock().ros_time_is_active:
            self.begin_turn(turn)
        # On simulation time the stop goes out right after the /clock message that ends the
        # turn, when the world has just stepped. A start sent at once, on the time of the last
        # /clock, could reach the world after its next steps had begun: the robot would turn
        # from a tick later than the server counts, and stop on time, short of the angle.

    def begin_turn(self, turn):
        """Publish the turn's command and schedule its stop exactly time_duration later."""
        now = self.get_clock().now()
        if self.cmd_vel_pub.get_subscription_count() == 0 and \
                turn.ticks_without_listener < self.publish_rate:
            # Nobody listens on cmd_vel yet (discovery takes a moment): a command sent now
            # would be lost and the turn would come up short. Try again for up to a second.
            turn.ticks_without_listener += 1
            return
        self.cmd_vel_pub.publish(turn.command)
        turn.start = now
        self.stop_timer.timer_period_ns = turn.time_duration * 1_000_000_000
        self.stop_timer.reset()
        self.get_logger().info(
            f'Robot Turning... {turn.command.angular.z} rad/s for {turn.time_duration} s')

    def publish_callback(self):
        """Repeat the current turn's command so the robot keeps turning."""
        if not self.turns:
            return
        turn = self.turns[0]
        if turn.start is None:
            self.begin_turn(turn)
        else:
            self.cmd_vel_pub.publish(turn.command)

    def stop_callback(self):
        """End the current turn: the timer fires when its time_duration has passed."""
        self.stop_timer.cancel()
        elapsed = (self.get_clock().now() - self.turns[0].start).nanoseconds / 1e9
        self.get_logger().info(f'Done ... after {elapsed:.3f} s')
        self.finish_turn()

    def time_moved(self, jump):
        """Begin a turn waiting for simulation time; end the turn under way if time went back."""
        if not self.turns:
            return
        if jump.delta.nanoseconds > 0:
            # Tried once: while nobody listens on cmd_vel, the publish timer tries again.
            if self.turns[0].start is None and self.turns[0].ticks_without_listener == 0:
                self.begin_turn(self.turns[0])
            return
        if self.turns[0].start is None:
            return
        turn = self.turns[0]
        before_jump = self.get_clock().now().nanoseconds - jump.delta.nanoseconds
        elapsed = (before_jump - turn.start.nanoseconds) / 1e9
        self.stop_timer.cancel()
        self.get_logger().warning(
            f'simulation time jumped back by {-jump.delta.nanoseconds / 1e9:.2f} s '
            f'(the simulation was reset): turn of {turn.command.angular.z} rad/s for '
            f'{turn.time_duration} s ended after {elapsed:.3f} s')
        self.finish_turn(success=False)

    def finish_turn(self, success=True):
        """Stop the robot, answer the current turn's caller, and start the next turn."""
        self.publish_timer.cancel()
        self.cmd_vel_pub.publish(Twist())
        self.turns.popleft().done.set_result(success)
        if self.turns:
            self.start_turn(self.turns[0])

    def destroy_node(self):
        """Stop the robot if the node goes away in the middle of a turn."""
        if self.turns and self.context.ok():
            self.cmd_vel_pub.publish(Twist())
        self.time_jump_handle.unregister()
        return super().destroy_node()


def main(args=None):
    """Run the turning server until Ctrl-C."""
    return spin_node(RobotTurningServer, args=args)


if __name__ == '__main__':
    main()
