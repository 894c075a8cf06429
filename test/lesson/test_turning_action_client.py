"""The turning action client: its input rules without ROS, then the program against a server."""

import math
import os
import re
import signal
import subprocess
from types import SimpleNamespace

from ament_index_python.packages import get_package_prefix
from geometry_msgs.msg import Twist
import pytest
from rclpy.parameter import Parameter
from service_tutorial.lesson.robot_turning_action_client import ANGLE_PROMPT, ANGLE_TOO_LARGE
from service_tutorial.lesson.robot_turning_action_client import ask_turning_goal, parse_arguments
from service_tutorial.lesson.robot_turning_action_client import parse_turning_goal
from service_tutorial.lesson.robot_turning_action_client import VELOCITY_NOT_POSITIVE
from service_tutorial.lesson.robot_turning_action_server import RobotTurningActionServer
from service_tutorial.lesson.turning_limits import NOT_A_NUMBER, TurningInputError
from service_tutorial.lesson.turning_limits import VELOCITY_PROMPT, VELOCITY_TOO_HIGH
from test_turning_action_server import ActionWorld, GroundTruth

CLIENT = os.path.join(get_package_prefix('service_tutorial'), 'lib', 'service_tutorial',
                      'robot_turning_action_client')


@pytest.mark.parametrize('angle, velocity, expected', [
    ('1.5708', '0.5', (1.5708, 0.5)),
    (' -3 ', '1.5707', (-3.0, 1.5707)),
    ('0', '0.1', (0.0, 0.1)),
    ('-62.83', '1', (-62.83, 1.0)),
])
def test_valid_input_becomes_a_goal(angle, velocity, expected):
    assert parse_turning_goal(angle, velocity) == expected


@pytest.mark.parametrize('angle, velocity, message', [
    ('abc', '0.5', NOT_A_NUMBER),
    ('1', 'fast', NOT_A_NUMBER),
    ('', '', NOT_A_NUMBER),
    ('nan', '0.5', NOT_A_NUMBER),
    ('1', 'inf', NOT_A_NUMBER),
    ('1', '2.0', VELOCITY_TOO_HIGH),
    ('1', '1.5708', VELOCITY_TOO_HIGH),
    ('1', '0', VELOCITY_NOT_POSITIVE),
    ('1', '-0.5', VELOCITY_NOT_POSITIVE),
    ('100', '0.5', ANGLE_TOO_LARGE),
    ('-62.9', '0.5', ANGLE_TOO_LARGE),
])
def test_invalid_input_is_refused_like_the_lessons_client(angle, velocity, message):
    with pytest.raises(TurningInputError) as error:
        parse_turning_goal(angle, velocity)
    assert str(error.value) == message


def test_prompts_again_until_a_valid_pair_is_typed():
    typed = iter(['abc', '0.5', '1', '2.0', '1', '0', '1.5708', '0.5', 'never read'])
    prompts = []
    errors = []
    logger = SimpleNamespace(error=errors.append)  # a node's logger, keeping the errors

    def read(prompt):
        prompts.append(prompt)
        return next(typed)

    assert ask_turning_goal(logger, read=read) == (1.5708, 0.5)
    assert errors == [NOT_A_NUMBER, VELOCITY_TOO_HIGH, VELOCITY_NOT_POSITIVE]
    assert prompts == [ANGLE_PROMPT, VELOCITY_PROMPT] * 4


def test_end_of_input_ends_the_prompting():
    def read(prompt):
        raise EOFError

    with pytest.raises(EOFError):
        ask_turning_goal(SimpleNamespace(error=[].append), read=read)


def test_arguments_give_the_goal_without_prompting():
    assert parse_arguments(['1.5708', '0.5']).goal == (1.5708, 0.5)
    assert parse_arguments(['-1.5708', '0.5']).goal == (-1.5708, 0.5)
    assert parse_arguments([]).goal is None
    for wrong in (['1'], ['1', '3.0'], ['x', '0.5'], ['1', '0'], ['1000', '0.5']):
        with pytest.raises(SystemExit) as exit_info:
            parse_arguments(wrong)
        assert exit_info.value.code == 2


def run_client(*args, stdin=''):
    return subprocess.run([CLIENT, *args], input=stdin, capture_output=True, text=True,
                          timeout=60)


def test_help_and_end_of_input_need_no_ros_graph():
    assert 'angular_vel' in run_client('--help').stdout

    finished = run_client(stdin='')

    assert finished.returncode == 1
    assert 'Traceback' not in finished.stderr


def progress(stdout):
    """Return the angles of the progress lines, in the order printed."""
    return [float(turned) for turned in re.findall(r'^turned +(-?\d+\.\d+) of', stdout, re.M)]


@pytest.fixture
def action_world(ros):
    action_world = ActionWorld(ros)
    yield action_world
    action_world.destroy()


@pytest.mark.ros
def test_prompted_client_sends_the_first_valid_pair_and_follows_it(action_world):
    finished = run_client(stdin='abc\n0.5\n1\n2.0\n0.5\n1.0\n')

    assert finished.returncode == 0, finished.stderr
    assert finished.stdout.count(ANGLE_PROMPT) == 3
    assert NOT_A_NUMBER in finished.stderr and VELOCITY_TOO_HIGH in finished.stderr
    turned = progress(finished.stdout)
    assert len(turned) >= 3 and turned == sorted(turned)
    assert 'status: SUCCEEDED\nsuccess: True\nangle_turned: ' in finished.stdout
    reported = float(finished.stdout.split('angle_turned: ')[1].split()[0])
    assert reported == pytest.approx(0.5, abs=0.01)


@pytest.mark.ros
def test_client_with_arguments_turns_right_without_prompting(action_world):
    truth = GroundTruth(action_world)
    truth.wait_at_rest()

    finished = run_client('-0.5', '1.0')

    assert finished.returncode == 0, finished.stderr
    assert ANGLE_PROMPT not in finished.stdout
    assert finished.stdout.startswith('goal accepted: turning -0.5 rad at up to 1.0 rad/s\n')
    assert 'status: SUCCEEDED' in finished.stdout
    truth.wait_at_rest()
    assert truth.turned == pytest.approx(-0.5, rel=0.02)


@pytest.mark.ros
def test_a_goal_the_server_rejects_is_reported(ros):
    ros.add_node(RobotTurningActionServer(
        parameter_overrides=[Parameter('max_angular_vel', value=0.5)]))

    finished = run_client('1.0', '1.0')

    assert finished.returncode == 1
    assert finished.stdout.strip() == 'goal rejected (the server log says why)'


@pytest.mark.ros
def test_ctrl_c_cancels_the_goal_and_tinybot_stops(action_world, start_program):
    truth = GroundTruth(action_world)
    truth.wait_at_rest()
    before = truth.last
    client = start_program([CLIENT, '2.0', '0.5'])
    for line in client.stdout:
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


@pytest.mark.ros
def test_a_reader_that_goes_away_ends_the_client_quietly(action_world, start_program):
    client = start_program([CLIENT, '2.0', '0.5'])
    for line in client.stdout:
        if progress(line):
            break
    client.stdout.close()  # as `robot_turning_action_client 2.0 0.5 | head -2` would
    errors = client.stderr.read()
    assert client.wait(timeout=30) == 1

    assert 'Traceback' not in errors
