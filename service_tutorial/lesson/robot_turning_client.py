"""
The lesson's turning client: ask /control_robot_angle to turn tinybot.

Run without arguments it prompts for the duration and the angular velocity, as the ROS 1
lesson did, and asks again until both are valid. Run as `robot_turning_client 2 0.5` it sends
the request without prompting, for scripts. When the answer is success false (a refused
request, or a turn that a reset of the simulation cut short) it says so on stderr and exits with
status 1.
"""

import argparse
import sys

import rclpy
from rclpy.node import Node
from service_tutorial.lesson.model_services import response_text
from service_tutorial.lesson.turning_input import ask_turning_request, given_or_asked
from service_tutorial.lesson.turning_input import MAX_ANGULAR_VEL
from service_tutorial.lesson.turning_input import parse_pair_or_nothing, parse_turning_request
from service_tutorial.node_main import program_arguments, run_node
from srv_interfaces.srv import ControlTurningMessage

# What success false means; the answer has no room for the reason, the server's log has it.
NOT_CARRIED_OUT = ('the turn was refused or cut short (a reset of the simulation ends a turn '
                   "under way); the server's log says why")


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
    request = given_or_asked(parse_arguments(program_arguments(args)).request,
                             ask_turning_request, 'robot_turning_client')
    if request is None:
        return 1

    def turn(node):
        if not node.wait_for_server():
            return 1
        future = node.send_request(*request)
        rclpy.spin_until_future_complete(node, future)
        response = future.result()
        print(response_text(response))
        if not response.success:
            print(f'robot_turning_client: {NOT_CARRIED_OUT}', file=sys.stderr)
        return 0 if response.success else 1
    return run_node(RobotTurningClient, turn, args=args)


if __name__ == '__main__':
    sys.exit(main())
