"""The turning action client program against a real action server (input: test_turning_input)."""

import math
import re
import signal

from geometry_msgs.msg import Twist
from programs import lines_of, program_path, run_program
import pytest
from rclpy.parameter import Parameter
from service_tutorial.lesson.robot_turning_action_client import ANGLE_PROMPT
from service_tutorial.lesson.robot_turning_action_server import RobotTurningActionServer
from service_tutorial.lesson.turning_input import NOT_A_NUMBER, VELOCITY_TOO_HIGH
from srv_interfaces.action import TurnRobot
from test_turning_action_server import GroundTruth as SteppedGroundTruth

pytestmark = pytest.mark.ros
CLIENT = program_path('robot_turning_action_client')
# Wall time between two samples of the ground truth, each a service call: in real time tinybot
# turns at most 0.016 rad in it, far less than the half turn that unwrapping allows.
SAMPLE_PERIOD = 0.01
# Wall-clock patience for tinybot to come to rest; what is asserted is in simulation time.
REST_TIMEOUT = 60.0


class ActionWorld:
    """The world in real time, as the client program meets it, and the action server."""

    def __init__(self, ros):
        self.ros = ros
        self.world = ros.start_world(real_time_factor=1.0)
        self.server = ros.add_node(RobotTurningActionServer(
            parameter_overrides=[Parameter('use_sim_time', value=True)]))
        self.cmd_vel = ros.subscribe(Twist, '/cmd_vel')
        action_client = ros.action_client(TurnRobot, '/turn_robot')
        assert action_client.wait_for_server(timeout_sec=10.0)

    def state(self):
        state = self.world.state('tinybot', 'world')
        assert state.success, state.status_message
        return state


class GroundTruth(SteppedGroundTruth):
    """The same ground truth of a world in real time: sampled every SAMPLE_PERIOD of wall time."""

    def follow_until(self, predicate):
        """Keep sampling until predicate() holds; return whether it came to hold."""
        return self.action_world.ros.wait_for(
            lambda: self.sample() and predicate(), timeout=REST_TIMEOUT, period=SAMPLE_PERIOD)


def progress(stdout):
    """Return the angles of the progress lines, in the order printed."""
    return [float(turned) for turned in re.findall(r'^turned +(-?\d+\.\d+) of', stdout, re.M)]


@pytest.fixture
def action_world(ros):
    return ActionWorld(ros)


def test_prompted_client_sends_the_first_valid_pair_and_follows_it(action_world):
    finished = run_program('robot_turning_action_client', stdin='abc\n0.5\n1\n2.0\n0.5\n1.0\n')

    assert finished.returncode == 0, finished.stderr
    assert finished.stdout.count(ANGLE_PROMPT) == 3
    assert NOT_A_NUMBER in finished.stderr and VELOCITY_TOO_HIGH in finished.stderr
    turned = progress(finished.stdout)
    assert len(turned) >= 3 and turned == sorted(turned)
    assert 'status: SUCCEEDED\nsuccess: True\nangle_turned: ' in finished.stdout
    reported = float(finished.stdout.split('angle_turned: ')[1].split()[0])
    assert reported == pytest.approx(0.5, abs=0.01)


def test_client_with_arguments_turns_right_without_prompting(action_world):
    truth = GroundTruth(action_world)
    truth.wait_at_rest()

    finished = run_program('robot_turning_action_client', '-0.5', '1.0', stdin='')

    assert finished.returncode == 0, finished.stderr
    assert ANGLE_PROMPT not in finished.stdout
    assert finished.stdout.startswith('goal accepted: turning -0.5 rad at up to 1.0 rad/s\n')
    assert 'status: SUCCEEDED' in finished.stdout
    truth.wait_at_rest()
    assert truth.turned == pytest.approx(-0.5, rel=0.02)


def test_a_goal_the_server_rejects_is_reported(ros):
    ros.add_node(RobotTurningActionServer(
        parameter_overrides=[Parameter('max_angular_vel', value=0.5)]))

    finished = run_program('robot_turning_action_client', '1.0', '1.0', stdin='')

    assert finished.returncode == 1
    assert finished.stdout.strip() == 'goal rejected (the server log says why)'


def test_ctrl_c_cancels_the_goal_and_tinybot_stops(action_world, start_program):
    truth = GroundTruth(action_world)
    truth.wait_at_rest()
    before = truth.last
    client = start_program([CLIENT, '2.0', '0.5'])
    for line in lines_of(client):
        if progress(line) and progress(line)[0] > 0.2:
            break
    client.send_signal(signal.SIGINT)
    rest, errors = client.communicate(timeout=30)

    assert client.returncode == 1, errors
    assert 'Traceback' not in errors
    assert 'canceling the goal ...\nstatus: CANCELED\nsuccess: False\n' in rest
    reported = float(re.search(r'^angle_turned: (-?\d+\.\d+)$', rest, re.M).group(1))
    # The robot stops and stays stopped, as ground truth over simulation time shows.
    truth.follow_for(0.3)
    assert abs(truth.yaw_rate) < 0.05
    assert action_world.server.turn is None
    assert action_world.cmd_vel[-1] == Twist()
    truth.wait_at_rest()
    turned = math.remainder(truth.last - before, math.tau)
    assert 0.2 < reported < 1.9
    assert reported == pytest.approx(turned, abs=0.02)


@pytest.mark.long
def test_a_reader_that_goes_away_ends_the_client_quietly(action_world, start_program):
    client = start_program([CLIENT, '2.0', '0.5'])
    for line in lines_of(client):
        if progress(line):
            break
    client.stdout.close()  # as `robot_turning_action_client 2.0 0.5 | head -2` would
    errors = client.stderr.read()
    assert client.wait(timeout=30) == 1

    assert 'Traceback' not in errors


def test_client_prints_why_a_reset_aborted_the_goal(action_world, start_program):
    client = start_program([CLIENT, '3.0', '0.5'])
    for line in lines_of(client):
        if progress(line) and progress(line)[0] > 0.2:
            break

    action_world.world.empty('reset_simulation')

    rest, errors = client.communicate(timeout=10)
    assert client.returncode == 1, errors
    assert 'Traceback' not in errors
    assert re.search(r'^status: ABORTED\nsuccess: False\n', rest, re.M), rest
    # Whichever the server hears first, /clock or the odometry stamp, names the jump.
    assert re.search(r'^message: "(simulation|odometry) time jumped back by \d+\.\d+ s '
                     r'\(the simulation was reset\): turned \d', rest, re.M), rest
