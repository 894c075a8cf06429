"""Spawning, deleting and resetting through the world's services, as functions and programs."""

import math

from geometry_msgs.msg import Pose
from programs import run_program
import pytest
from rclpy.node import Node
from service_tutorial.conversions import make_pose, yaw_of
from service_tutorial.lesson.model_services import delete_model, get_model_state, model_path
from service_tutorial.lesson.model_services import reset_simulation, response_text
from service_tutorial.lesson.model_services import ServiceUnavailableError, spawn_model
from srv_interfaces.srv import SpawnModel
from std_srvs.srv import Empty


@pytest.mark.parametrize('yaw', [0.0, 0.3, -math.pi / 2, 3.0])
def test_make_pose_and_yaw_of_agree(yaw):
    pose = make_pose(1.0, 2.0, 3.0, yaw=yaw)

    assert (pose.position.x, pose.position.y, pose.position.z) == (1.0, 2.0, 3.0)
    assert yaw_of(pose.orientation) == pytest.approx(yaw)


def test_lesson_quaternion_is_a_quarter_turn_to_the_right():
    pose = make_pose(quaternion=(0.0, 0.0, -0.707, 0.707))

    assert yaw_of(pose.orientation) == pytest.approx(-math.pi / 2)
    with pytest.raises(ValueError):
        make_pose(yaw=0.0, quaternion=(0.0, 0.0, 0.0, 1.0))


def test_responses_print_the_way_ros_1_printed_them():
    response = SpawnModel.Response(success=True, status_message='spawned "r2d2"')

    assert response_text(response) == 'success: True\nstatus_message: "spawned \\"r2d2\\""'


def test_spawn_model_wants_exactly_one_model_description():
    with pytest.raises(ValueError):
        spawn_model(None, 'r2d2')
    with pytest.raises(ValueError):
        spawn_model(None, 'r2d2', model_xml='<robot/>', model_file='r2d2.urdf')


@pytest.mark.ros
@pytest.mark.long
def test_lesson_programs_spawn_delete_and_reset(ros):
    world = ros.start_world(paused=True)

    spawned = run_program('spawn_model_client')

    assert spawned.returncode == 0, spawned.stderr
    assert spawned.stdout.startswith('success: True\nstatus_message: "')
    state = get_model_state(ros.client_node, 'r2d2')
    assert state.success, state.status_message
    assert state.pose.position.x == pytest.approx(-2.0, abs=0.02)
    assert state.pose.position.y == pytest.approx(1.0, abs=0.02)
    assert math.degrees(yaw_of(state.pose.orientation)) == pytest.approx(-90.0, abs=1.0)

    deleted = run_program('delete_model_client', 'r2d2')

    assert deleted.returncode == 0, deleted.stderr
    assert 'success: True' in deleted.stdout
    assert world.models() == ['tinybot']
    assert run_program('delete_model_client', 'r2d2').returncode == 1

    assert world.step(500) == pytest.approx(1.0, abs=1e-9)
    reset = run_program('reset_simulation_client')

    assert reset.returncode == 0, reset.stderr
    assert ros.wait_for(lambda: world.now() == 0.0)


@pytest.mark.ros
def test_functions_call_the_world_from_a_spinning_node(ros):
    world = ros.start_world()
    node = ros.client_node

    spawned = spawn_model(node, 'r2d2', model_file=model_path('r2d2.urdf'),
                          pose=make_pose(1.0, 2.0, 0.5, yaw=0.3))

    assert spawned.success, spawned.status_message
    state = get_model_state(node, 'r2d2')
    assert (state.pose.position.x, state.pose.position.y) == pytest.approx((1.0, 2.0), abs=0.02)
    assert yaw_of(state.pose.orientation) == pytest.approx(0.3, abs=0.02)

    assert delete_model(node, 'r2d2').success
    assert world.models() == ['tinybot']
    gone = delete_model(node, 'r2d2')
    assert not gone.success and 'r2d2' in gone.status_message

    assert isinstance(reset_simulation(node), Empty.Response)


@pytest.mark.ros
def test_functions_spin_a_node_no_executor_owns(ros):
    world = ros.start_world()
    node = Node('lesson_script')
    try:
        with open(model_path('r2d2.urdf')) as urdf_file:
            spawned = spawn_model(node, 'r2d2', model_xml=urdf_file.read(), pose=Pose())

        assert spawned.success, spawned.status_message
        assert node.executor is None
        assert 'r2d2' in world.models()
        assert delete_model(node, 'r2d2').success
    finally:
        node.destroy_node()


@pytest.mark.ros
def test_a_missing_service_raises_an_error_naming_it(rclpy_session):
    # No world in this namespace: the relative names resolve under /nowhere. How soon the
    # error comes is the benchmark's business (its answers table).
    node = Node('lesson_script', namespace='/nowhere')
    try:
        with pytest.raises(ServiceUnavailableError, match='/nowhere/mujoco/delete_model'):
            delete_model(node, 'r2d2', timeout=0.5)
    finally:
        node.destroy_node()

    missing = run_program('delete_model_client', '--timeout', '0.5',
                          '--ros-args', '-r', '__ns:=/nowhere')

    assert missing.returncode == 1
    assert 'service /nowhere/mujoco/delete_model did not appear within 0.5 s' in missing.stderr
    assert issubclass(ServiceUnavailableError, TimeoutError)
