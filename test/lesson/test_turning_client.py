"""The turning client: its input rules without ROS, then the program against a real server."""

import os
import subprocess
from types import SimpleNamespace

from ament_index_python.packages import get_package_prefix
from geometry_msgs.msg import Twist
import pytest
from service_tutorial.lesson.robot_turning_client import parse_arguments
from service_tutorial.lesson.robot_turning_server import RobotTurningServer
from service_tutorial.lesson.turning_limits import ask_turning_request, DURATION_NOT_WHOLE
from service_tutorial.lesson.turning_limits import DURATION_PROMPT, NOT_A_NUMBER
from service_tutorial.lesson.turning_limits import parse_turning_request, TurningInputError
from service_tutorial.lesson.turning_limits import VELOCITY_PROMPT, VELOCITY_TOO_HIGH

CLIENT = os.path.join(get_package_prefix('service_tutorial'), 'lib', 'service_tutorial',
                      'robot_turning_client')


@pytest.mark.parametrize('duration, velocity, expected', [
    ('2', '0.5', (2, 0.5)),
    (' 3 ', '-1.5707', (3, -1.5707)),
    ('0', '0', (0, 0.0)),
    ('5.0', '1', (5, 1.0)),
])
def test_valid_input_becomes_a_request(duration, velocity, expected):
    assert parse_turning_request(duration, velocity) == expected


@pytest.mark.parametrize('duration, velocity, message', [
    ('abc', '0.5', NOT_A_NUMBER),
    ('2', 'fast', NOT_A_NUMBER),
    ('', '', NOT_A_NUMBER),
    ('2', 'nan', NOT_A_NUMBER),
    ('inf', '0.5', NOT_A_NUMBER),
    ('2', '2.0', VELOCITY_TOO_HIGH),
    ('2', '-1.6', VELOCITY_TOO_HIGH),
    ('-1', '0.5', DURATION_NOT_WHOLE),
    ('1.5', '0.5', DURATION_NOT_WHOLE),
    ('5000000000', '0.5', DURATION_NOT_WHOLE),
])
def test_invalid_input_is_refused_with_the_lessons_message(duration, velocity, message):
    with pytest.raises(TurningInputError, match=message.replace('!', '\\!')):
        parse_turning_request(duration, velocity)


def test_prompts_again_until_a_valid_pair_is_typed():
    typed = iter(['abc', '0.5', '2', '2.0', '2', '0.5', 'never read', 'never read'])
    prompts = []
    errors = []
    logger = SimpleNamespace(error=errors.append)  # a node's logger, keeping the errors

    def read(prompt):
        prompts.append(prompt)
        return next(typed)

    assert ask_turning_request(logger, read=read) == (2, 0.5)
    assert errors == [NOT_A_NUMBER, VELOCITY_TOO_HIGH]
    assert prompts == [DURATION_PROMPT, VELOCITY_PROMPT] * 3


def test_end_of_input_ends_the_prompting():
    def read(prompt):
        raise EOFError

    with pytest.raises(EOFError):
        ask_turning_request(SimpleNamespace(error=[].append), read=read)


def test_arguments_give_the_request_without_prompting():
    assert parse_arguments(['2', '0.5']).request == (2, 0.5)
    assert parse_arguments(['1', '-0.3']).request == (1, -0.3)
    assert parse_arguments([]).request is None
    for wrong in (['2'], ['2', '3.0'], ['x', '0.5']):
        with pytest.raises(SystemExit) as exit_info:
            parse_arguments(wrong)
        assert exit_info.value.code == 2


def run_client(*args, stdin=''):
    return subprocess.run([CLIENT, *args], input=stdin, capture_output=True, text=True,
                          timeout=30)


def test_help_and_end_of_input_need_no_ros_graph():
    assert 'angular_vel' in run_client('--help').stdout

    finished = run_client(stdin='')

    assert finished.returncode == 1
    assert 'Traceback' not in finished.stderr


@pytest.mark.ros
def test_prompted_client_sends_the_first_valid_pair(ros):
    ros.add_node(RobotTurningServer())
    cmd_vel = ros.subscribe(Twist, '/cmd_vel')

    finished = run_client(stdin='abc\n0.5\n1\n2.0\n1\n0.25\n')

    assert finished.returncode == 0, finished.stderr
    assert finished.stdout.count(DURATION_PROMPT) == 3
    assert NOT_A_NUMBER in finished.stderr and VELOCITY_TOO_HIGH in finished.stderr
    assert 'waiting for /control_robot_angle' in finished.stderr
    assert finished.stdout.rstrip().endswith('success: True')
    assert ros.wait_for(lambda: cmd_vel and cmd_vel[-1] == Twist())
    assert {msg.angular.z for msg in cmd_vel} == {0.25, 0.0}


@pytest.mark.ros
def test_client_with_arguments_sends_without_prompting(ros):
    ros.add_node(RobotTurningServer())
    cmd_vel = ros.subscribe(Twist, '/cmd_vel')

    finished = run_client('1', '-0.3')

    assert finished.returncode == 0, finished.stderr
    assert DURATION_PROMPT not in finished.stdout
    assert finished.stdout.strip() == 'success: True'
    assert ros.wait_for(lambda: cmd_vel and cmd_vel[-1] == Twist())
    assert {msg.angular.z for msg in cmd_vel} == {-0.3, 0.0}
