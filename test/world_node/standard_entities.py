"""What the standard entity tests share: requests in the standard's own types, and checks."""

import math

from geometry_msgs.msg import PoseStamped
from repository import read_model, TEST_MODELS
from service_tutorial.conversions import make_pose
from simulation_interfaces.msg import Result
from simulation_interfaces.srv import GetEntities, GetEntityState, SpawnEntity

CRATE = ('<robot name="crate"><link name="body"><inertial><mass value="2"/><inertia ixx="0.05" '
         'iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>'
         '<box size="0.4 0.4 0.4"/></geometry></collision></link></robot>')


def red_box():
    """Return the URDF of a box fixed to the world: a static object."""
    return read_model('props/red_box', TEST_MODELS)


def stamped(x=0.0, y=0.0, z=0.0, *, yaw=None, frame='', quaternion=None):
    """Return a PoseStamped in a frame, orientation as yaw or as (x, y, z, w)."""
    message = PoseStamped()
    message.header.frame_id = frame
    message.pose = make_pose(x, y, z, yaw=yaw, quaternion=quaternion)
    return message


def spawn(world, *, timeout=10.0, **fields):
    """Call /spawn_entity with the fields of a SpawnEntity request; return the response."""
    return world.call(SpawnEntity, '/spawn_entity', SpawnEntity.Request(**fields),
                      timeout=timeout)


def spawn_or_fail(world, **fields):
    """Spawn an entity the test needs; fail with the world's answer if it is refused."""
    response = spawn(world, **fields)
    assert response.result.result == Result.RESULT_OK, response.result.error_message
    return response.entity_name


def entities(world, filters=None, *, timeout=10.0):
    """Return the GetEntities response for filters (an EntityFilters), all when None."""
    request = GetEntities.Request()
    if filters is not None:
        request.filters = filters
    return world.call(GetEntities, '/get_entities', request, timeout=timeout)


def entity_state(world, name):
    """Return the GetEntityState response of an entity."""
    return world.call(GetEntityState, '/get_entity_state', GetEntityState.Request(entity=name))


def position_of(world, name):
    """Return an entity's position in the world, through the standard."""
    response = entity_state(world, name)
    assert response.result.result == Result.RESULT_OK, response.result.error_message
    position = response.state.pose.position
    return (position.x, position.y, position.z)


def close(first, second, tolerance=1e-6):
    """Return True if two sequences of numbers agree within tolerance."""
    return all(math.isclose(a, b, abs_tol=tolerance) for a, b in zip(first, second))


def snapshot(world):
    """Return every model's name and exact pose and twist, through the lesson's services."""
    states = {}
    for name in world.models():
        state = world.state(name)
        states[name] = (state.pose, state.twist)
    return states
