"""
The lesson's turning client: ask /control_robot_angle to turn tinybot.

Run without arguments it prompts for the duration and the angular velocity, as the ROS 1
lesson did, and asks again until both are valid. Run as `robot_turning_client 2 0.5` it sends
the request without prompting, for scripts.
"""

import argparse
import math
import sys

import rclpy
from rclpy.node import Node
from service_tutorial.client_main import program_arguments, run_node
from service_tutorial.model_services import response_text
from service_tutorial.robot_turning_server import MAX_ANGULAR_VEL
from srv_interfaces.srv import ControlTurningMessage

MAX_UINT32 = 2**32 - 1
DURATION_PROMPT = '> Type turning time duration: '
VELOCITY_PROMPT = '> Type turning angular velocity: '
NOT_A_NUMBER = 'Not a number type number plz !!'
VELOCITY_TOO_HIGH = 'Velocity too high !!'
DURATION_NOT_WHOLE = 'Duration must be a whole number of seconds, 0 or more !!'


class TurningInputError(ValueError):
    """A typed duration or velocity that cannot go into the request."""


def parse_turning_request(duration_text, velocity_text, *, max_angular_vel=MAX_ANGULAR_VEL):
    """Turn the typed duration and velocity into (time_duration, angular_vel) or raise."""
    try:
        duration = float(duration_text)
        velocity = float(velocity_text)
    except ValueError:
        raise TurningInputError(NOT_A_NUMBER) from None
    if not (math.isfinite(duration) and math.isfinite(velocity)):
        raise TurningInputError(NOT_A_NUMBER)
    if duration < 0 or duration != int(duration) or duration > MAX_UINT32:
        raise TurningInputError(DURATION_NOT_WHOLE)
    if abs(velocity) > max_angular_vel:
        raise TurningInputError(VELOCITY_TOO_HIGH)
    return int(duration), velocity


def ask_turning_request(logger, *, read=input, prompts=(DURATION_PROMPT, VELOCITY_PROMPT),
                        parse=parse_turning_request):
    """Prompt for two values (duration, velocity) until parse takes them; EOFError at the end."""
    while True:
        first_text = read(prompts[0])
        velocity_text = read(prompts[1])
        try:
            return parse(first_text, velocity_text)
        except TurningInputError as error:
            logger.error(str(error))


class RobotTurningClient(Node):
    """Sends one turning request to /control_robot_angle."""

    def __init__(self, **kwargs):
        super().__init__('robot_turning_client', **kwargs)
        self.turning_cli = self.create_client(ControlTurningMessage, 'control_robot_angle')

    def wait_for_server(self):
        """Wait until the turning service is up, saying so; False if ROS shut down first."""
        if not self.turning_cli.service_is_ready():
            self.get_logger().info(f'waiting for {self.turning_cli.service_name} ...')
        return self.turning_cli.wait_for_service()

    def send_request(self, time_duration, angular_vel):
        """Ask for a turn; return the future of the response."""
        request = ControlTurningMessage.Request()
        request.time_duration = time_duration
        request.angular_vel = angular_vel
        return self.turning_cli.call_async(request)


def parse_pair_or_nothing(argv, parser, names, parse, result):
    """
    Read the two positionals names through parse() into options.<result>, None if not given.

    The lesson's clients take both numbers on the command line or prompt for them; a bad
    pair ends the program with argparse's usage line and the reason.
    """
    first, second = names
    options = parser.parse_args(argv)
    values = (getattr(options, first), getattr(options, second))
    if (values[0] is None) != (values[1] is None):
        parser.error(f'give both {first} and {second}, or neither to be prompted')
    setattr(options, result, None)
    if values[0] is not None:
        try:
            setattr(options, result, parse(*values))
        except TurningInputError as error:
            parser.error(str(error))
    return options


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    parser = argparse.ArgumentParser(
        prog='robot_turning_client',
        description='Ask /control_robot_angle to turn the robot; prompts when given nothing.')
    parser.add_argument('time_duration', nargs='?',
                        help='how long to turn, in whole seconds')
    parser.add_argument('angular_vel', nargs='?',
                        help=f'turning rate in rad/s, at most {MAX_ANGULAR_VEL} either way')
    return parse_pair_or_nothing(argv, parser, ('time_duration', 'angular_vel'),
                                 parse_turning_request, 'request')


def main(args=None):
    """Ask for one turn and print the answer; exit status 0 when the turn succeeded."""
    options = parse_arguments(program_arguments(args))
    request = options.request
    if request is None:
        # Prompt before rclpy takes over Ctrl-C, so that Ctrl-C at a prompt stops the program.
        try:
            request = ask_turning_request(rclpy.logging.get_logger('robot_turning_client'))
        except (EOFError, KeyboardInterrupt):
            print()
            return 1

    def turn(node):
        if not node.wait_for_server():
            return 1
        future = node.send_request(*request)
        rclpy.spin_until_future_complete(node, future)
        response = future.result()
        print(response_text(response))
        return 0 if response.success else 1
    return run_node(RobotTurningClient, turn, args=args)


if __name__ == '__main__':
    sys.exit(main())
