"""
Turning as an action, from the command line: ask turn_robot to turn tinybot and watch it.

Run without arguments it prompts for the angle and the angular velocity the way the lesson's
robot_turning_client does, with the same refusals. Run as `robot_turning_action_client 1.5708
0.5` it sends the goal without prompting. It prints the server's feedback as a progress line
and the result at the end. Ctrl-C cancels the goal: the robot stops, the result (what was
turned) is printed, and the program exits.
"""

import argparse
import os
import sys
import threading

from action_msgs.msg import GoalStatus
import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from service_tutorial.lesson.goal_client import GoalClient
from service_tutorial.lesson.model_services import response_text
from service_tutorial.lesson.turning_input import ask_turning_request, given_or_asked
from service_tutorial.lesson.turning_input import MAX_ANGLE, MAX_ANGULAR_VEL
from service_tutorial.lesson.turning_input import parse_pair_or_nothing, TurningInputError
from service_tutorial.lesson.turning_input import typed_numbers, VELOCITY_PROMPT
from service_tutorial.lesson.turning_input import VELOCITY_TOO_HIGH
from service_tutorial.node_main import program_arguments
from srv_interfaces.action import TurnRobot

ANGLE_PROMPT = '> Type turning angle: '
VELOCITY_NOT_POSITIVE = 'Velocity must be above 0 (a negative angle turns right) !!'
ANGLE_TOO_LARGE = f'Angle too large: at most {MAX_ANGLE:.4f} rad (10 turns) either way !!'
STATUS_NAMES = {getattr(GoalStatus, name): name[len('STATUS_'):]
                for name in dir(GoalStatus) if name.startswith('STATUS_')}


class FollowError(RuntimeError):
    """The goal cannot be followed any more: the server went away, or the node stopped."""


def parse_turning_goal(angle_text, velocity_text):
    """Turn the typed angle and velocity into (angle, angular_vel) or raise."""
    angle, velocity = typed_numbers(angle_text, velocity_text)
    if velocity > MAX_ANGULAR_VEL:
        raise TurningInputError(VELOCITY_TOO_HIGH)
    if not velocity > 0.0:
        raise TurningInputError(VELOCITY_NOT_POSITIVE)
    if abs(angle) > MAX_ANGLE:
        raise TurningInputError(ANGLE_TOO_LARGE)
    return angle, velocity


def ask_turning_goal(logger, *, read=input):
    """Prompt for an angle and a velocity until both are valid; EOFError if input ends."""
    return ask_turning_request(logger, read=read, prompts=(ANGLE_PROMPT, VELOCITY_PROMPT),
                               parse=parse_turning_goal)


def progress_text(feedback, angle):
    """Format one feedback message as a progress line."""
    share = 100.0 if angle == 0.0 else 100.0 * feedback.angle_turned / angle
    return (f'turned {feedback.angle_turned:7.3f} of {angle:.3f} rad ({share:3.0f} %), '
            f'{feedback.angle_remaining:.3f} rad to go')


class RobotTurningActionClient(Node):
    """Sends one goal to turn_robot and follows it to its end."""

    def __init__(self, **kwargs):
        super().__init__('robot_turning_action_client', **kwargs)
        self.turn_robot_client = GoalClient(self, TurnRobot, 'turn_robot')
        self.action_name = self.resolve_service_name('turn_robot')
        self.angle = 0.0
        # On a terminal each report overwrites the last; in a pipe each gets a line.
        self.on_terminal = sys.stdout.isatty()
        self.progress_shown = False
        self.output_closed = False
        self.spinner = None
        # Feedback is shown until the goal is being cancelled or has ended; the lock keeps a
        # report from coming after the line that says so.
        self.following = True
        self.output_lock = threading.Lock()

    def spin_in_background(self):
        """Spin in a thread of its own, leaving the main thread free to take Ctrl-C at once."""
        executor = SingleThreadedExecutor(context=self.context)
        executor.add_node(self)
        self.spinner = threading.Thread(target=executor.spin, daemon=True)
        self.spinner.start()
        return executor

    def wait_for_server(self):
        """Wait until the action server is up, saying so; False if ROS shut down first."""
        if not self.turn_robot_client.server_is_ready():
            self.get_logger().info(f'waiting for {self.action_name} ...')
        return self.turn_robot_client.wait_for_server()

    def send_goal(self, angle, angular_vel):
        """Ask for a turn; return the future of the goal handle."""
        self.angle = angle
        goal = TurnRobot.Goal(angle=angle, angular_vel=angular_vel)
        return self.turn_robot_client.send_goal_async(
            goal, feedback_callback=self.feedback_callback)

    def feedback_callback(self, feedback_msg):
        """Show how far the robot has turned, while the goal is followed."""
        text = progress_text(feedback_msg.feedback, self.angle)
        with self.output_lock:
            if self.following:
                self.show_progress(text)

    def show_progress(self, text):
        """Print a progress line: over the last one on a terminal."""
        try:
            if self.on_terminal:
                # Back to the start of the line, write, clear what a longer report left.
                print(f'\r{text}\x1b[K', end='', flush=True)
            else:
                print(text, flush=True)
        except BrokenPipeError:
            # The reader has gone (`| head`); the main thread ends the program.
            self.output_closed = True
        self.progress_shown = True

    def end_progress(self):
        """Stop showing feedback; move past a progress line the next would have overwritten."""
        with self.output_lock:
            self.following = False
            if self.on_terminal and self.progress_shown:
                print()
            self.progress_shown = False

    def wait(self, future):
        """Wait for a future the spinning thread completes; Ctrl-C interrupts the wait."""
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        # Event.wait gives way to Ctrl-C at once; a look now and then notices what went wrong.
        while not done.wait(1.0):
            if self.output_closed:
                raise BrokenPipeError('standard output was closed')
            if not self.spinner.is_alive():
                raise FollowError('the node stopped spinning (the error is above)')
            if not self.turn_robot_client.server_is_ready():
                raise FollowError(f'{self.action_name} went away before answering')
        return future.result()

    def turn(self, angle, angular_vel):
        """Send the goal and follow it; Ctrl-C cancels it. Return the final status and result."""
        goal_future = self.send_goal(angle, angular_vel)
        interrupted = False
        try:
            goal_handle = self.wait(goal_future)
        except KeyboardInterrupt:
            # The goal may be accepted all the same: wait for the answer to cancel it.
            interrupted = True
            goal_handle = self.wait(goal_future)
        if not goal_handle.accepted:
            return None, None
        print(f'goal accepted: turning {angle} rad at up to {angular_vel} rad/s', flush=True)
        result_future = goal_handle.get_result_async()
        if not interrupted:
            try:
                self.wait(result_future)
            except KeyboardInterrupt:
                interrupted = True
        if interrupted:
            self.end_progress()
            print('canceling the goal ...', flush=True)
            self.wait(goal_handle.cancel_goal_async())
        response = self.wait(result_future)
        self.end_progress()
        return response.status, response.result


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    parser = argparse.ArgumentParser(
        prog='robot_turning_action_client',
        description='Ask the turn_robot action to turn the robot by an angle and follow it; '
                    'prompts when given nothing. Ctrl-C cancels the turn.')
    parser.add_argument('angle', nargs='?',
                        help='how far to turn, in rad (positive turns left)')
    parser.add_argument('angular_vel', nargs='?',
                        help=f'top turning speed in rad/s, above 0 and at most {MAX_ANGULAR_VEL}')
    return parse_pair_or_nothing(argv, parser, ('angle', 'angular_vel'), parse_turning_goal,
                                 'goal')


def main(args=None):
    """Ask for one turn, follow it, print the result; exit status 0 when it succeeded."""
    goal = given_or_asked(parse_arguments(program_arguments(args)).goal, ask_turning_goal,
                          'robot_turning_action_client')
    if goal is None:
        return 1
    # Ctrl-C must not shut ROS down: the cancel still has to reach the server. The node spins
    # in a thread of its own and the main thread waits, where Ctrl-C interrupts it at once.
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    node = executor = None
    status = 1
    try:
        node = RobotTurningActionClient()
        executor = node.spin_in_background()
        if node.wait_for_server():
            goal_status, result = node.turn(*goal)
            if result is None:
                print('goal rejected (the server log says why)')
            else:
                print(f'status: {STATUS_NAMES.get(goal_status, goal_status)}')
                print(response_text(result))
                status = 0 if goal_status == GoalStatus.STATUS_SUCCEEDED else 1
    except FollowError as error:
        print(f'robot_turning_action_client: {error}', file=sys.stderr)
    except BrokenPipeError:
        # Nobody reads the output any more; keep Python from failing to flush it at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if executor is not None:
            executor.shutdown()
            node.spinner.join()
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return status


if __name__ == '__main__':
    sys.exit(main())
