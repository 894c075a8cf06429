"""srv_interfaces: the lesson's types exist as specified and carry data between two nodes."""

import math

from geometry_msgs.msg import Pose
import pytest
from rclpy.node import Node
from srv_interfaces.msg import RemovedModel
from srv_interfaces.srv import ControlTurningMessage, DeleteModel, GetModelList
from srv_interfaces.srv import GetModelState, SetModelState, SpawnModel

pytestmark = pytest.mark.ros


def test_control_turning_message_is_exactly_the_lesson_type():
    assert ControlTurningMessage.Request.get_fields_and_field_types() == {
        'time_duration': 'uint32', 'angular_vel': 'double'}
    assert ControlTurningMessage.Response.get_fields_and_field_types() == {'success': 'boolean'}


def test_spawn_and_delete_model_match_gazebo_msgs():
    assert SpawnModel.Request.get_fields_and_field_types() == {
        'model_name': 'string', 'model_xml': 'string', 'robot_namespace': 'string',
        'initial_pose': 'geometry_msgs/Pose', 'reference_frame': 'string'}
    assert SpawnModel.Response.get_fields_and_field_types() == {
        'success': 'boolean', 'status_message': 'string'}
    assert DeleteModel.Request.get_fields_and_field_types() == {'model_name': 'string'}
    assert DeleteModel.Response.get_fields_and_field_types() == {
        'success': 'boolean', 'status_message': 'string'}


def test_model_state_services_answer_success_and_status_message():
    for srv_type in (GetModelList, GetModelState, SetModelState):
        fields = srv_type.Response.get_fields_and_field_types()
        assert fields['success'] == 'boolean'
        assert fields['status_message'] == 'string'
    assert GetModelState.Response.get_fields_and_field_types()['pose'] == 'geometry_msgs/Pose'
    assert SetModelState.Request.get_fields_and_field_types()['twist'] == 'geometry_msgs/Twist'


def test_removed_model_names_the_model_the_reason_and_the_time():
    assert RemovedModel.get_fields_and_field_types() == {
        'stamp': 'builtin_interfaces/Time', 'model_name': 'string', 'reason': 'string'}


class EchoServer(Node):
    """Answers each interface from the request's own data, so the round trip is visible."""

    def __init__(self):
        super().__init__('interface_echo_server')
        self.requests = []
        self.turning_srv = self.create_service(
            ControlTurningMessage, 'control_robot_angle', self.turning_callback)
        self.spawn_srv = self.create_service(SpawnModel, 'spawn_urdf_model', self.spawn_callback)
        self.delete_srv = self.create_service(DeleteModel, 'delete_model', self.delete_callback)

    def turning_callback(self, request, response):
        self.requests.append(request)
        response.success = request.time_duration == 2 and request.angular_vel == 0.5
        return response

    def spawn_callback(self, request, response):
        self.requests.append(request)
        position = request.initial_pose.position
        response.success = True
        response.status_message = (
            f'{request.model_name} ({len(request.model_xml)} bytes) at '
            f'{position.x:g} {position.y:g} {position.z:g} '
            f'qz={request.initial_pose.orientation.z:g} in {request.reference_frame}')
        return response

    def delete_callback(self, request, response):
        self.requests.append(request)
        response.success = False
        response.status_message = f'no model named {request.model_name!r}'
        return response


def test_control_turning_message_round_trip(ros):
    server = ros.add_node(EchoServer())
    response = ros.call(ControlTurningMessage, 'control_robot_angle',
                        ControlTurningMessage.Request(time_duration=2, angular_vel=0.5))
    assert response.success is True
    assert server.requests[-1].time_duration == 2
    assert server.requests[-1].angular_vel == 0.5


def test_spawn_and_delete_model_round_trip(ros):
    server = ros.add_node(EchoServer())
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = -2.0, 1.0, 1.0
    pose.orientation.z, pose.orientation.w = -0.707, 0.707
    request = SpawnModel.Request(model_name='r2d2', model_xml='<robot name="r2d2"/>',
                                 robot_namespace='', initial_pose=pose, reference_frame='world')
    response = ros.call(SpawnModel, 'spawn_urdf_model', request)
    assert response.success is True
    assert response.status_message == 'r2d2 (20 bytes) at -2 1 1 qz=-0.707 in world'
    received = server.requests[-1].initial_pose
    assert math.isclose(received.orientation.w, 0.707)

    response = ros.call(DeleteModel, 'delete_model', DeleteModel.Request(model_name='r2d2'))
    assert response.success is False
    assert response.status_message == "no model named 'r2d2'"
