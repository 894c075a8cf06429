"""Entity states through the standard: get and set pose and twist, relative frames, refusals."""

from geometry_msgs.msg import Twist, Vector3
import pytest
from service_tutorial.conversions import seconds_of
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_robot
from service_tutorial.world_node.standard.entity_messages import EntityStates
from simulation_interfaces.msg import EntityState, Result
from simulation_interfaces.srv import SetEntityState
from standard_entities import close, CRATE, entity_state, red_box, snapshot, spawn_or_fail
from standard_entities import stamped

pytestmark = pytest.mark.ros


@pytest.fixture
def world(ros):
    """Start the default world, tinybot at the origin, paused so that states stay put."""
    return ros.start_world(paused=True, real_time_factor=0.0)


def set_state(world, name, pose, twist=None, frame=''):
    """Call /set_entity_state; return the response."""
    state = EntityState(pose=pose, twist=twist or Twist())
    state.header.frame_id = frame
    return world.call(SetEntityState, '/set_entity_state',
                      SetEntityState.Request(entity=name, state=state))


def spin(linear=(0.0, 0.0, 0.0), angular=(0.0, 0.0, 0.0)):
    """Return a Twist."""
    linear, angular = [float(value) for value in linear], [float(value) for value in angular]
    return Twist(linear=Vector3(x=linear[0], y=linear[1], z=linear[2]),
                 angular=Vector3(x=angular[0], y=angular[1], z=angular[2]))


def vector(message):
    """Return the (x, y, z) of a Point or Vector3."""
    return (message.x, message.y, message.z)


def test_set_pose_and_twist_at_once_and_read_them_back(world):
    answer = set_state(world, 'tinybot', stamped(1.0, -2.0, 0.1, yaw=0.5).pose,
                       spin(linear=(0.3, 0.0, 0.0), angular=(0.0, 0.0, 0.4)))
    assert answer.result.result == Result.RESULT_OK, answer.result.error_message
    state = entity_state(world, 'tinybot')
    assert state.result.result == Result.RESULT_OK
    assert state.state.header.frame_id == 'world'
    assert close(vector(state.state.pose.position), (1.0, -2.0, 0.1))
    assert close(vector(state.state.twist.linear), (0.3, 0.0, 0.0))
    assert close(vector(state.state.twist.angular), (0.0, 0.0, 0.4))


def test_a_state_relative_to_another_entity(world):
    spawn_or_fail(world, name='crate', resource_string=CRATE, initial_pose=stamped(3.0, 0, 0.2))
    assert set_state(world, 'tinybot', stamped(0.0, 1.0, 0.0, yaw=1.5708).pose).result.result \
        == Result.RESULT_OK
    answer = set_state(world, 'crate', stamped(2.0, 0.0, 0.2).pose, frame='tinybot')
    assert answer.result.result == Result.RESULT_OK, answer.result.error_message
    assert close(vector(entity_state(world, 'crate').state.pose.position), (0.0, 3.0, 0.2),
                 1e-4)


def test_acceleration_at_rest_is_nothing_and_falling_is_gravity(ros):
    world = ros.start_world(paused=True)
    spawn_or_fail(world, name='crate', resource_string=CRATE, initial_pose=stamped(3.0, 0, 50))
    world.step(100)  # 0.2 s
    falling = entity_state(world, 'crate').state.acceleration.linear
    assert close(vector(falling), (0.0, 0.0, -9.81), 1e-3)
    resting = entity_state(world, 'tinybot').state.acceleration.linear
    assert close(vector(resting), (0.0, 0.0, 0.0), 0.05)


def test_refusals_of_setting_a_state(world):
    spawn_or_fail(world, name='red_box', resource_string=red_box(),
                  initial_pose=stamped(0.0, -4.0))
    before = snapshot(world)
    nan_pose = stamped(float('nan'), 0.0, 0.0).pose
    zero_turn = stamped(quaternion=(0.0, 0.0, 0.0, 0.0)).pose
    for name, pose, twist, frame, code, message in [
            ('ghost', stamped().pose, None, '', Result.RESULT_NOT_FOUND,
             "SetEntityState: no entity named 'ghost'"),
            ('tinybot', nan_pose, None, '', SetEntityState.Response.INVALID_POSE,
             'SetEntityState: position contains NaN or infinity: [nan, 0.0, 0.0]'),
            ('tinybot', zero_turn, None, '', SetEntityState.Response.INVALID_POSE,
             'SetEntityState: orientation quaternion is zero'),
            ('tinybot', stamped().pose, None, 'nowhere', SetEntityState.Response.INVALID_POSE,
             "SetEntityState: state names frame 'nowhere', which is neither the world nor an "
             'entity'),
            ('tinybot', stamped().pose, spin(linear=(float('inf'), 0, 0)), '',
             Result.RESULT_OPERATION_FAILED, 'linear_velocity contains NaN or infinity'),
            ('tinybot', stamped().pose, spin(linear=(1e9, 0, 0)), '',
             Result.RESULT_OPERATION_FAILED, 'must stay below 100000 in magnitude'),
            ('red_box', stamped(0.0, -4.0).pose, spin(angular=(0, 0, 1.0)), '',
             Result.RESULT_OPERATION_FAILED,
             "SetEntityState: entity 'red_box' is a static object; it cannot be given a twist")]:
        answer = set_state(world, name, pose, twist, frame)
        assert answer.result.result == code, answer.result.error_message
        assert message in answer.result.error_message
    assert snapshot(world) == before
    # A static object may still be moved.
    assert set_state(world, 'red_box', stamped(0.0, -5.0).pose).result.result \
        == Result.RESULT_OK
    assert close(vector(entity_state(world, 'red_box').state.pose.position), (0.0, -5.0, 0.0))
    assert entity_state(world, 'ghost').result.result == Result.RESULT_NOT_FOUND


def numbers(state):
    """Return the stamp, frame, position, orientation (w, x, y, z), twist and acceleration."""
    orientation = state.pose.orientation
    return (seconds_of(state.header.stamp), state.header.frame_id, vector(state.pose.position),
            (orientation.w, orientation.x, orientation.y, orientation.z),
            vector(state.twist.linear), vector(state.twist.angular),
            vector(state.acceleration.linear), vector(state.acceleration.angular))


def test_kept_state_messages_are_refilled_with_each_call():
    world = World()
    for name, x in (('near', 0.0), ('far', 3.0)):
        spawn_robot(world, name, CRATE.replace('crate', name), position=(x, 0.0, 0.2))
    states = EntityStates(world)

    def in_world(name):
        state = world.get_model_state(name)
        return (world.time, 'world', tuple(state.position), tuple(state.orientation),
                tuple(state.linear_velocity), tuple(state.angular_velocity))

    first = [numbers(state)[:6] for state in states(['near', 'far'])]
    assert first == [in_world('near'), in_world('far')]
    world.set_model_state('near', position=(1.0, 2.0, 0.5), orientation=(0.0, 0.0, 0.0, 1.0),
                          linear_velocity=(0.5, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.3))
    world.step(5, even_if_paused=True)
    near, far = states(['near', 'far'])
    assert [numbers(near)[:6], numbers(far)[:6]] == [in_world('near'), in_world('far')]
    assert numbers(near)[2] != first[0][2] and world.time > 0.0
    # The first message kept now carries whichever entity is listed first.
    only, = states(['far'])
    assert only is near
    assert numbers(only)[:6] == in_world('far')
