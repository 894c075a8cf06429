"""
The lesson's world services, as gazebo_ros serves Gazebo's: spawn, delete, reset, pause, state.

They are the world node's services under its private namespace (/mujoco/ by default), with
srv_interfaces' copies of gazebo_msgs' types. A failure is data in the response (success false
and a status_message that says what went wrong), never a crashed node; a spawn or delete holds
simulation time for as long as it takes, so that a real-time world does not jump ahead after it.
"""

from rclpy.parameter import Parameter
from service_tutorial.conversions import fill_pose_msg, fill_twist_msg, pose_from_msg
from service_tutorial.conversions import time_msg, twist_from_msg
from service_tutorial.sim.robot_files import read_text
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.world_node.answers import lesson_answer, raise_refusal
from srv_interfaces.srv import DeleteModel, GetModelList, GetModelState, SetModelState
from srv_interfaces.srv import SpawnModel
from std_srvs.srv import Empty

URDF_ONLY = ('urdf',)  # as Gazebo's spawn_urdf_model


class GazeboServices:
    """The /mujoco/ services of the world node (node.MujocoWorld)."""

    def __init__(self, node):
        """Serve the world of node under node's private namespace."""
        self.node = node
        self.world = node.world
        self.spawn_srv = node.serve(
            SpawnModel, '~/spawn_urdf_model', self.spawn_model_callback)
        self.delete_srv = node.serve(
            DeleteModel, '~/delete_model', self.delete_model_callback)
        self.reset_simulation_srv = node.serve(
            Empty, '~/reset_simulation', self.reset_simulation_callback)
        self.reset_world_srv = node.serve(
            Empty, '~/reset_world', self.reset_world_callback)
        self.pause_srv = node.serve(
            Empty, '~/pause_physics', self.pause_physics_callback)
        self.unpause_srv = node.serve(
            Empty, '~/unpause_physics', self.unpause_physics_callback)
        self.model_list_srv = node.serve(
            GetModelList, '~/get_model_list', self.get_model_list_callback)
        self.get_state_srv = node.serve(
            GetModelState, '~/get_model_state', self.get_model_state_callback)
        self.set_state_srv = node.serve(
            SetModelState, '~/set_model_state', self.set_model_state_callback)

    def spawn_model_callback(self, request, response):
        """Spawn a URDF model as Gazebo's spawn_urdf_model; failures are answered, not raised."""
        def spawn():
            robot = read_text(request.model_xml, 'model_xml', formats=URDF_ONLY)
            position, orientation = pose_from_msg(request.initial_pose)
            order = SpawnOrder.of(request.model_name, robot, position=position,
                                  orientation=orientation,
                                  reference_frame=request.reference_frame)
            outcome, = self.node.spawn_models([order], [request.robot_namespace])
            left_out = raise_refusal(outcome)
            answer = f'SpawnModel: Successfully spawned entity {request.model_name!r}'
            return f'{answer} ({left_out})' if left_out else answer
        return lesson_answer(self.node, 'SpawnModel', response, self.node.holding_time(spawn))

    def delete_model_callback(self, request, response):
        """Delete a model and its topics."""
        def delete():
            self.node.delete_model(request.model_name)
            return f'DeleteModel: Successfully deleted model {request.model_name!r}'
        return lesson_answer(self.node, 'DeleteModel', response, self.node.holding_time(delete))

    def get_model_list_callback(self, request, response):
        """List every model in spawn order."""
        response.model_names = self.world.model_names()
        response.success = True
        response.status_message = 'GetModelList: got properties'
        return response

    def get_model_state_callback(self, request, response):
        """Report a model's pose and twist in the requested frame."""
        def get_state():
            state = self.world.get_model_state(request.model_name, request.reference_frame)
            response.header.stamp = time_msg(self.world.time)
            response.header.frame_id = request.reference_frame or 'world'
            fill_pose_msg(response.pose, state.position, state.orientation)
            fill_twist_msg(response.twist, state.linear_velocity, state.angular_velocity)
            return 'GetModelState: got properties'
        return lesson_answer(self.node, 'GetModelState', response, get_state)

    def set_model_state_callback(self, request, response):
        """Move a model to a pose and give it a twist."""
        def set_state():
            position, orientation = pose_from_msg(request.pose)
            linear, angular = twist_from_msg(request.twist)
            self.world.set_model_state(
                request.model_name, position=position, orientation=orientation,
                linear_velocity=linear, angular_velocity=angular,
                reference_frame=request.reference_frame)
            return f'SetModelState: set state of {request.model_name!r}'
        return lesson_answer(self.node, 'SetModelState', response, set_state)

    def reset_simulation_callback(self, request, response):
        """Put every model back at its spawn pose and the clock back to zero."""
        self.world.reset_simulation()
        self.node.after_reset()
        self.node.get_logger().info('simulation reset: time 0, every model at its spawn pose')
        return response

    def reset_world_callback(self, request, response):
        """Put every model back at its spawn pose; time goes on."""
        self.world.reset_world()
        self.node.after_reset()
        self.node.get_logger().debug('world reset: every model at its spawn pose')
        return response

    def pause_physics_callback(self, request, response):
        """Stop stepping; services and /clock keep answering. The paused parameter follows."""
        self.node.set_parameters([Parameter('paused', Parameter.Type.BOOL, True)])
        return response

    def unpause_physics_callback(self, request, response):
        """Resume stepping from where it stopped. The paused parameter follows."""
        self.node.set_parameters([Parameter('paused', Parameter.Type.BOOL, False)])
        return response
