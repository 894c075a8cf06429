"""
Generated robots, poses and commands thrown at the world core: it never crashes and stays finite.

Every attempt ends in success or a WorldError; after it the world steps, every state is finite,
tinybot is still there, and a refused spawn left tinybot exactly as it was. The examples are
derandomized and no example database is kept, so every run tries the same inputs.
"""

import math

from hypothesis import given
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
import numpy as np
from repository import TINYBOT
from service_tutorial.sim.plugins.diff_drive import MAX_WHEEL_RIM_SPEED
from service_tutorial.sim.validation import bounded, WorldError
from service_tutorial.testing.spawns import spawn_robot
from worlds import settled_world

PROPERTY_SETTINGS = settings(max_examples=60, derandomize=True, database=None, deadline=None,
                             suppress_health_check=[HealthCheck.too_slow])

# Half of the robots are well formed, if sometimes extreme: they reach the physics. The other
# half are hostile: now and then a number is not a number, a joint type does not exist, a mesh
# points outside, a joint closes a loop.
BAD_NUMBERS = st.sampled_from(['0', '-1', 'nan', 'inf', '-inf', '1e300', 'abc', ''])
EXTREME_NUMBERS = st.sampled_from(['1e-9', '1e-6', '1e6', '1e9'])
GOOD_JOINT_TYPES = st.sampled_from(['fixed', 'revolute', 'continuous', 'prismatic'])
BAD_JOINT_TYPES = st.sampled_from(['floating', 'planar', 'hinge', 'ball', ''])
MESHES = st.sampled_from(['file:///etc/shadow', '../../../../etc/passwd', 'mesh.obj',
                          'package://no_such_package/m.stl', 'package://service_tutorial/x.stl',
                          'http://example.com/m.obj', ''])
REALS = st.one_of(st.floats(min_value=-5.0, max_value=5.0),
                  st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e9, 0.0]))


def rarely(draw, hostile, unusual, usual):
    """Draw from unusual now and then if hostile, else from usual."""
    if hostile and draw(st.integers(0, 19)) == 0:
        return draw(unusual)
    return draw(usual)


@st.composite
def numbers(draw, hostile, low=0.01, high=2.0):
    if draw(st.integers(0, 29)) == 0:
        return draw(EXTREME_NUMBERS)
    return rarely(draw, hostile, BAD_NUMBERS,
                  st.floats(min_value=low, max_value=high).map(lambda value: f'{value:.3g}'))


@st.composite
def triples(draw, hostile, low=-1.0):
    return ' '.join(draw(numbers(hostile, low)) for _ in range(3))


@st.composite
def origins(draw, hostile):
    if draw(st.booleans()):
        return ''
    return f'<origin xyz="{draw(triples(hostile))}" rpy="{draw(triples(hostile))}"/>'


@st.composite
def geometries(draw, hostile):
    kind = rarely(draw, hostile, st.sampled_from(['mesh', 'empty']),
                  st.sampled_from(['box', 'cylinder', 'sphere']))
    size = numbers(hostile)
    if kind == 'box':
        shape = f'<box size="{draw(triples(hostile, 0.01))}"/>'
    elif kind == 'cylinder':
        shape = f'<cylinder radius="{draw(size)}" length="{draw(size)}"/>'
    elif kind == 'sphere':
        shape = f'<sphere radius="{draw(size)}"/>'
    elif kind == 'mesh':
        shape = f'<mesh filename="{draw(MESHES)}"/>'
    else:
        shape = ''
    return f'{draw(origins(hostile))}<geometry>{shape}</geometry>'


@st.composite
def links(draw, name, hostile):
    parts = []
    if rarely(draw, hostile, st.just(False), st.just(True)):
        value = numbers(hostile)
        # Equal moments always satisfy the triangle inequality of a real body.
        moment = draw(value)
        moments = [rarely(draw, hostile, value, st.just(moment)) for _ in range(3)]
        products = [rarely(draw, hostile, numbers(hostile, -1.0), st.just('0'))
                    for _ in range(3)]
        parts.append(
            f'<inertial>{draw(origins(hostile))}<mass value="{draw(value)}"/>'
            f'<inertia ixx="{moments[0]}" iyy="{moments[1]}" izz="{moments[2]}" '
            f'ixy="{products[0]}" ixz="{products[1]}" iyz="{products[2]}"/></inertial>')
    for tag in draw(st.lists(st.sampled_from(['visual', 'collision']), max_size=3)):
        parts.append(f'<{tag}>{draw(geometries(hostile))}</{tag}>')
    return f'<link name="{name}">{"".join(parts)}</link>'


@st.composite
def joints(draw, index, names, hostile):
    kind = rarely(draw, hostile, BAD_JOINT_TYPES, GOOD_JOINT_TYPES)
    # Usually a tree; now and then a loop, a link of its own, a missing link or the world.
    parent = rarely(draw, hostile, st.sampled_from(names + ['ghost', 'world']),
                    st.sampled_from(names[:index]))
    parts = [draw(origins(hostile))]
    if draw(st.booleans()):
        parts.append(f'<axis xyz="{draw(triples(hostile))}"/>')
    if kind in ('revolute', 'prismatic') or draw(st.integers(0, 4)) == 0:
        parts.append(f'<limit lower="-{draw(numbers(hostile))}" '
                     f'upper="{draw(numbers(hostile))}" effort="{draw(numbers(hostile))}" '
                     f'velocity="{draw(numbers(hostile))}"/>')
    if draw(st.booleans()):
        parts.append(f'<dynamics damping="{draw(numbers(hostile))}" '
                     f'friction="{draw(numbers(hostile))}"/>')
    return (f'<joint name="j{index}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{names[index]}"/>{"".join(parts)}</joint>')


@st.composite
def robots(draw):
    """Return URDF text of a random tree of links, and whether it carries a diff drive."""
    hostile = draw(st.booleans())
    count = draw(st.integers(1, 5))
    names = [f'l{index}' for index in range(count)]
    parts = [draw(links(name, hostile)) for name in names]
    parts += [draw(joints(index, names, hostile)) for index in range(1, count)]
    drive = count >= 3 and draw(st.booleans())
    if drive:
        parts.append(
            '<gazebo><plugin name="drive" filename="libgazebo_ros_diff_drive.so">'
            f'<left_joint>j1</left_joint><right_joint>j2</right_joint>'
            f'<wheel_separation>{draw(numbers(hostile))}</wheel_separation>'
            f'<wheel_diameter>{draw(numbers(hostile))}</wheel_diameter>'
            f'<max_wheel_torque>{draw(numbers(hostile))}</max_wheel_torque>'
            '</plugin></gazebo>')
    return f'<robot name="generated">{"".join(parts)}</robot>', drive


def tinybot_world():
    """Return a world with tinybot, settled for a tenth of a second."""
    return settled_world('tinybot', TINYBOT, steps=50)


def everything(world):
    """Return every state of the world as one vector."""
    data = world.data
    return np.concatenate([data.qpos, data.qvel, data.act, data.ctrl])


def assert_sound(world):
    """Check that tinybot is there and that every model's state is finite."""
    assert 'tinybot' in world.model_names()
    assert np.isfinite(everything(world)).all()
    for name in world.model_names():
        state = world.get_model_state(name)
        assert np.isfinite(np.concatenate([state.position, state.orientation,
                                           state.linear_velocity,
                                           state.angular_velocity])).all()
    odometry = world.models['tinybot'].drive().odometry()
    assert np.isfinite(np.concatenate([odometry.position, odometry.linear_velocity])).all()


@PROPERTY_SETTINGS
@given(robot=robots(), position=st.tuples(REALS, REALS, REALS),
       orientation=st.tuples(REALS, REALS, REALS, REALS),
       command=st.tuples(REALS, REALS))
def test_generated_robots_are_spawned_or_refused_and_the_world_stays_sound(
        robot, position, orientation, command):
    xml, drive = robot
    world = tinybot_world()
    before = everything(world)
    try:
        spawn_robot(world, 'generated', xml, position=position, orientation=orientation)
    except WorldError as error:
        assert str(error)
        assert world.model_names() == ['tinybot']
        np.testing.assert_array_equal(everything(world), before)
    world.step(100)
    assert_sound(world)
    if drive and 'generated' in world.models:
        try:
            world.models['generated'].drive().command_velocity(*command)
        except WorldError as error:
            assert 'NaN or infinite' in str(error)
        world.step(100)
        assert_sound(world)
    if 'generated' in world.models:
        world.delete_model('generated')
    assert world.model_names() == ['tinybot']
    world.step(10)
    assert_sound(world)


@PROPERTY_SETTINGS
@given(moves=st.lists(st.tuples(st.tuples(REALS, REALS, REALS),
                                st.tuples(REALS, REALS, REALS, REALS),
                                st.tuples(REALS, REALS, REALS),
                                st.tuples(REALS, REALS, REALS),
                                st.tuples(REALS, REALS)), min_size=1, max_size=4))
def test_any_set_state_and_command_leaves_the_world_finite(moves):
    world = tinybot_world()
    for position, orientation, linear, angular, command in moves:
        try:
            world.set_model_state('tinybot', position=position, orientation=orientation,
                                  linear_velocity=linear, angular_velocity=angular)
        except WorldError as error:
            assert str(error)
        try:
            linear_x, angular_z = world.models['tinybot'].drive().command_velocity(*command)
        except WorldError as error:
            assert 'NaN or infinite' in str(error)
        else:
            config = world.models['tinybot'].drive().config
            rim = max(abs(linear_x - angular_z * config.wheel_separation / 2.0),
                      abs(linear_x + angular_z * config.wheel_separation / 2.0))
            assert rim <= MAX_WHEEL_RIM_SPEED * (1.0 + 1e-12)
        world.step(50)
        assert_sound(world)


@PROPERTY_SETTINGS
@given(st.lists(st.one_of(st.floats(allow_nan=True, allow_infinity=True),
                          st.floats(min_value=-2e5, max_value=2e5)), max_size=500),
       st.sampled_from([1e5, 1e8, 1e10]))
def test_a_state_check_agrees_with_looking_at_every_value(values, limit):
    """Whether a state is sane does not depend on the sum of squares that settles most."""
    array = np.array(values, dtype=float)
    every_value = all(math.isfinite(value) and abs(value) < limit for value in values)
    assert bounded(array, limit) == every_value
