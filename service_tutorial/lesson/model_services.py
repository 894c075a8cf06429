"""
Plain functions that call the world's model services from any node.

They are the ROS 2 counterparts of the lesson's GazeboSpawnModel, GazeboDeleteModel and
GazeboResetSimulation: spawn_model(), delete_model() and reset_simulation() each call one
service of the MuJoCo world and return its response. A failure the world reports is data in
the response (success false, status_message says why); a service that does not appear, or does
not answer, within the timeout raises an error that names it.

Waiting for an answer depends on who spins the node:

- a node that no executor owns (a script's node) is spun here, by a private executor, until
  the answer arrives;
- a node that an executor owns is assumed to be spinning in another thread, which delivers the
  answer, and the call only waits for it.

Do not call these functions from a callback of a single-threaded executor that spins the same
node: that thread would be waiting for an answer only it can deliver, and the call times out.
From a callback, use a MultiThreadedExecutor (each call here has a callback group of its own,
so its answer never waits behind the calling callback) or await client.call_async() in an
async callback.
"""

import os
import threading
import time

from ament_index_python.packages import get_package_share_directory
from geometry_msgs.msg import Pose
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from service_tutorial.sim.robot_files import read_path
from srv_interfaces.srv import DeleteModel, GetModelState, SpawnModel
from std_srvs.srv import Empty

PACKAGE = 'service_tutorial'
# Service names relative to the calling node's namespace: /mujoco/... from the root namespace.
SPAWN_MODEL_SERVICE = 'mujoco/spawn_urdf_model'
DELETE_MODEL_SERVICE = 'mujoco/delete_model'
RESET_SIMULATION_SERVICE = 'mujoco/reset_simulation'
GET_MODEL_STATE_SERVICE = 'mujoco/get_model_state'
DEFAULT_TIMEOUT = 10.0


class ServiceUnavailableError(TimeoutError):
    """A service did not appear within the timeout."""


class ServiceTimeoutError(TimeoutError):
    """A service was called but did not answer within the timeout."""


def model_path(file_name, *, package=PACKAGE):
    """Return the path of a model file in a package's share/<package>/models folder."""
    return os.path.join(get_package_share_directory(package), 'models', file_name)


def response_text(response):
    """Format a response's fields one per line, the way ROS 1 printed them."""
    lines = []
    for field in response.get_fields_and_field_types():
        value = getattr(response, field)
        if isinstance(value, str):
            value = '"' + value.replace('"', '\\"') + '"'
        lines.append(f'{field}: {value}')
    return '\n'.join(lines)


def call_service(node, srv_type, service_name, request, *, timeout=DEFAULT_TIMEOUT):
    """Call a service through a client made for this one call; return its response."""
    # A callback group of its own lets a multi-threaded executor deliver the answer while the
    # callback that made this call still holds the node's default group.
    client = node.create_client(
        srv_type, service_name, callback_group=MutuallyExclusiveCallbackGroup())
    try:
        return call(node, client, request, timeout=timeout)
    finally:
        node.destroy_client(client)


def call(node, client, request, *, timeout=DEFAULT_TIMEOUT):
    """
    Call a service through a client of node and return its response.

    Raises ServiceUnavailableError when the service does not appear within timeout seconds and
    ServiceTimeoutError when it appears but does not answer within timeout seconds.
    """
    if not client.wait_for_service(timeout_sec=timeout):
        if not node.context.ok():
            raise ExternalShutdownException()
        raise ServiceUnavailableError(
            f'service {client.service_name} did not appear within {timeout} s '
            f'(is the node that serves it running?)')
    future = client.call_async(request)
    if not wait_for_future(node, future, timeout=timeout):
        client.remove_pending_request(future)
        raise ServiceTimeoutError(
            f'service {client.service_name} did not answer within {timeout} s')
    return future.result()


def wait_for_future(node, future, *, timeout):
    """Wait until a future is done, spinning node if no executor owns it; return if it is."""
    if node.executor is None:
        executor = SingleThreadedExecutor(context=node.context)
        try:
            executor.add_node(node)
            executor.spin_until_future_complete(future, timeout_sec=timeout)
        finally:
            executor.remove_node(node)
            # remove_node() leaves the node pointing at the executor; hand the node back free.
            node.executor = None
            executor.shutdown()
        return future.done()
    answered = threading.Event()
    future.add_done_callback(lambda _: answered.set())
    deadline = time.monotonic() + timeout
    # Wake up now and then to notice a shutdown (Ctrl-C) that stops the spinning thread.
    while not answered.wait(min(0.1, max(0.0, deadline - time.monotonic()))):
        if not node.context.ok():
            raise ExternalShutdownException()
        if time.monotonic() >= deadline:
            return False
    return True


def spawn_model(node, name, *, model_xml=None, model_file=None, pose=None, namespace='',
                reference_frame='world', xacro_arguments=None, timeout=DEFAULT_TIMEOUT):
    """
    Spawn a URDF model in the world; return the SpawnModel response.

    Give the URDF as text (model_xml) or as a path (model_file), which may be a xacro file:
    it is expanded here, with xacro_arguments {name: value}, and a WorldError (of
    sim/robot_files.py) says why it could not be. pose is a geometry_msgs/Pose in
    reference_frame (default: the origin; conversions.make_pose builds one); namespace puts
    the model's topics under it.
    """
    if (model_xml is None) == (model_file is None):
        raise ValueError('give the model as model_xml or as model_file, exactly one of them')
    if model_file is not None:
        model_xml = read_path(model_file, xacro_arguments=xacro_arguments,
                              formats=('urdf',)).text
    request = SpawnModel.Request()
    request.model_name = name
    request.model_xml = model_xml
    request.robot_namespace = namespace
    request.initial_pose = pose if pose is not None else Pose()
    request.reference_frame = reference_frame
    return call_service(node, SpawnModel, SPAWN_MODEL_SERVICE, request, timeout=timeout)


def delete_model(node, name, *, timeout=DEFAULT_TIMEOUT):
    """Delete a model from the world; return the DeleteModel response."""
    request = DeleteModel.Request()
    request.model_name = name
    return call_service(node, DeleteModel, DELETE_MODEL_SERVICE, request, timeout=timeout)


def reset_simulation(node, *, timeout=DEFAULT_TIMEOUT):
    """Put the simulation back to time zero with every model at its spawn pose."""
    return call_service(node, Empty, RESET_SIMULATION_SERVICE, Empty.Request(),
                        timeout=timeout)


def get_model_state(node, name, *, reference_frame='world', timeout=DEFAULT_TIMEOUT):
    """Read a model's pose and twist; return the GetModelState response."""
    request = GetModelState.Request()
    request.model_name = name
    request.reference_frame = reference_frame
    return call_service(node, GetModelState, GET_MODEL_STATE_SERVICE, request, timeout=timeout)
