"""The turning client program against a real turning server (input rules: test_turning_input)."""

from geometry_msgs.msg import Twist
from programs import program_path, run_program
import pytest
from rclpy.parameter import Parameter
from service_tutorial.lesson.robot_turning_client import NOT_CARRIED_OUT
from service_tutorial.lesson.robot_turning_server import RobotTurningServer
from service_tutorial.lesson.turning_input import DURATION_PROMPT, NOT_A_NUMBER
from service_tutorial.lesson.turning_input import VELOCITY_TOO_HIGH

pytestmark = pytest.mark.ros


def test_prompted_client_sends_the_first_valid_pair(ros):
    ros.add_node(RobotTurningServer())
    cmd_vel = ros.subscribe(Twist, '/cmd_vel')

    finished = run_program('robot_turning_client', stdin='abc\n0.5\n1\n2.0\n1\n0.25\n')

    assert finished.returncode == 0, finished.stderr
    assert finished.stdout.count(DURATION_PROMPT) == 3
    assert NOT_A_NUMBER in finished.stderr and VELOCITY_TOO_HIGH in finished.stderr
    assert finished.stdout.rstrip().endswith('success: True')
    assert ros.wait_for(lambda: cmd_vel and cmd_vel[-1] == Twist())
    assert {msg.angular.z for msg in cmd_vel} == {0.25, 0.0}


def test_client_with_arguments_sends_without_prompting(ros):
    ros.add_node(RobotTurningServer())
    cmd_vel = ros.subscribe(Twist, '/cmd_vel')

    finished = run_program('robot_turning_client', '1', '-0.3', stdin='')

    assert finished.returncode == 0, finished.stderr
    assert DURATION_PROMPT not in finished.stdout
    assert finished.stdout.strip() == 'success: True'
    assert ros.wait_for(lambda: cmd_vel and cmd_vel[-1] == Twist())
    assert {msg.angular.z for msg in cmd_vel} == {-0.3, 0.0}


def test_client_started_before_the_server_says_it_waits_then_sends(ros, start_program):
    client = start_program([program_path('robot_turning_client'), '1', '0.2'])
    waiting = client.stderr.readline()  # the server does not exist yet: it must wait
    assert 'waiting for /control_robot_angle' in waiting, waiting

    ros.add_node(RobotTurningServer())

    stdout, stderr = client.communicate(timeout=30)
    assert client.returncode == 0, stderr
    assert stdout.strip() == 'success: True'


def test_client_says_when_a_reset_cut_the_turn_short(ros, start_program):
    world = ros.start_world()
    ros.add_node(RobotTurningServer(parameter_overrides=[Parameter('use_sim_time', value=True)]))
    cmd_vel = ros.subscribe(Twist, '/cmd_vel')
    client = start_program([program_path('robot_turning_client'), '10', '0.5'])
    assert ros.wait_for(lambda: any(msg.angular.z == 0.5 for msg in cmd_vel), timeout=30.0)
    world.wait_sim(0.5)

    world.empty('reset_simulation')

    stdout, stderr = client.communicate(timeout=10)
    assert client.returncode == 1, stderr
    assert stdout.strip() == 'success: False'
    assert f'robot_turning_client: {NOT_CARRIED_OUT}' in stderr
