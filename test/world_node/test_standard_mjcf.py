"""
MJCF entities through the standard's SpawnEntity, on the running world, in the standard's types.

An MJCF object by resource_string and an MJCF robot by package:// uri spawn, fall and rest
(stepped with StepSimulation, physics paused), the robot's joint_states carry its joint, and
both answer the lesson's services and the standard's. Hostile MJCF gets its code and a message
naming the value, and every other entity keeps its exact state.
"""

import os
import shutil

import pytest
from repository import install_package, MJCF_ARM, MJCF_CRATE, read_file, TEST_MODELS
from sensor_msgs.msg import JointState
from simulation_interfaces.msg import EntityCategory, Resource, Result
from simulation_interfaces.msg import SpawnEntity as SpawnRequest, SpawnResult
from simulation_interfaces.srv import DeleteEntity, GetEntityBounds, GetEntityInfo
from simulation_interfaces.srv import GetSimulatorFeatures, SpawnEntities, StepSimulation
from standard_entities import close, entity_state, position_of, snapshot, spawn
from standard_entities import spawn_or_fail, stamped

pytestmark = pytest.mark.ros

CRATE = read_file(MJCF_CRATE)
ARM = read_file(MJCF_ARM)


@pytest.fixture
def world(ros):
    """Start the default world, tinybot at the origin, paused: StepSimulation moves it."""
    return ros.start_world(paused=True, real_time_factor=0.0)


@pytest.fixture
def mjcf_package(tmp_path, monkeypatch):
    """Install a package of MJCF files: an arm, a mesh box, and files that reach out of it."""
    share = install_package(tmp_path, monkeypatch, 'mjcf_pkg')
    (share / 'meshes').mkdir(parents=True)
    (share / 'arm.xml').write_text(ARM)
    shutil.copy(os.path.join(TEST_MODELS, 'meshes', 'box.obj'), share / 'meshes' / 'box.obj')
    shutil.copy(os.path.join(TEST_MODELS, 'meshes', 'box.obj'), tmp_path / 'outside.obj')
    (share / 'meshes' / 'link.obj').symlink_to(tmp_path / 'outside.obj')
    (tmp_path / 'outside.xml').write_text(CRATE)
    (share / 'escape.xml').symlink_to(tmp_path / 'outside.xml')
    for name, filename in (('boxy', 'box.obj'), ('dotdot', '../../../../outside.obj'),
                           ('linked', 'link.obj'), ('absent', 'absent.obj')):
        (share / f'{name}.mjcf').write_text(mesh_box(name, filename))
    (share / 'huge.xml').write_text(CRATE + ' ' * (10 * 1024 * 1024))
    return share


def mesh_box(name, filename):
    """Return an MJCF body with a freejoint and a mesh read from meshes/<filename>."""
    return (f'<mujoco model="{name}"><compiler meshdir="meshes"/><asset><mesh name="box" '
            f'file="{filename}"/></asset><worldbody><body name="box"><freejoint/>'
            '<geom type="mesh" mesh="box" mass="1"/></body></worldbody></mujoco>')


def step(world, steps):
    """Step the paused world with StepSimulation; fail if it does not."""
    result = world.call(StepSimulation, '/step_simulation',
                        StepSimulation.Request(steps=steps), timeout=60.0).result
    assert result.result == Result.RESULT_OK, result.error_message


def at_rest(world, name):
    """Tell whether an entity's twist is all but zero, through GetEntityState."""
    twist = entity_state(world, name).state.twist
    return max(abs(value) for value in (twist.linear.x, twist.linear.y, twist.linear.z,
                                        twist.angular.x, twist.angular.y,
                                        twist.angular.z)) < 1e-3


def test_mjcf_is_a_spawn_format(world):
    features = world.call(GetSimulatorFeatures, '/get_simulator_features',
                          GetSimulatorFeatures.Request()).features
    assert 'mjcf' in features.spawn_formats and 'urdf' in features.spawn_formats


def test_an_mjcf_object_and_robot_spawn_fall_and_rest(world, mjcf_package, ros):
    assert spawn_or_fail(world, resource_string=CRATE,
                         initial_pose=stamped(2.0, 0.0, 1.0)) == 'crate'
    assert spawn_or_fail(world, uri='package://mjcf_pkg/arm.xml', entity_namespace='arm',
                         initial_pose=stamped(-2.0, 0.0, 0.0)) == 'arm'
    assert spawn_or_fail(world, uri='package://mjcf_pkg/boxy.mjcf',
                         initial_pose=stamped(0.0, 2.0, 0.5)) == 'boxy'
    assert world.models() == ['tinybot', 'crate', 'arm', 'boxy']
    # The arm's top body stands 0.3 m up in its file, relative to the spawn pose.
    assert close(position_of(world, 'arm'), (-2.0, 0.0, 0.3))
    joint_states = ros.subscribe(JointState, '/arm/joint_states')
    assert ros.wait_for(lambda: world.node.models['arm'].topics_made)
    step(world, 100)
    assert position_of(world, 'crate')[2] < 0.95  # falling
    step(world, 1000)
    assert close(position_of(world, 'crate'), (2.0, 0.0, 0.1), 1e-3)  # half its height
    assert close(position_of(world, 'arm'), (-2.0, 0.0, 0.05), 1e-3)
    assert close(position_of(world, 'boxy'), (0.0, 2.0, 0.02), 1e-3)  # its mesh 0.04 m high
    assert all(at_rest(world, name) for name in ('crate', 'arm', 'boxy'))
    assert ros.wait_for(lambda: joint_states, timeout=10.0), 'no joint_states from the arm'
    assert list(joint_states[-1].name) == ['shoulder']
    assert abs(joint_states[-1].position[0]) < 1e-3
    # The lesson's services and the standard's see them as they see a URDF robot.
    assert world.state('crate').pose.position.z == pytest.approx(0.1, abs=1e-3)
    bounds = world.call(GetEntityBounds, '/get_entity_bounds',
                        GetEntityBounds.Request(entity='crate')).bounds.points
    assert close((bounds[1].x, bounds[1].y, bounds[1].z), (0.1, 0.1, 0.1))
    categories = {name: world.call(GetEntityInfo, '/get_entity_info', GetEntityInfo.Request(
        entity=name)).info.category.category for name in ('crate', 'arm')}
    assert categories == {'crate': EntityCategory.CATEGORY_OBJECT,
                          'arm': EntityCategory.CATEGORY_ROBOT}
    # Deleting one and spawning another keeps every other entity's exact state.
    before = snapshot(world)
    deleted = world.call(DeleteEntity, '/delete_entity', DeleteEntity.Request(entity='crate'))
    assert deleted.result.result == Result.RESULT_OK, deleted.result.error_message
    del before['crate']
    assert snapshot(world) == before
    spawn_or_fail(world, name='crate2', resource_string=CRATE,
                  initial_pose=stamped(3.0, 0.0, 1.0))
    assert {name: state for name, state in snapshot(world).items()
            if name != 'crate2'} == before
    assert world.delete('arm').success
    assert '/arm/joint_states' not in world.published_topics()


HOSTILE_MJCF = [
    ({'resource_string': '<mujoco><include file="other.xml"/><worldbody><body/></worldbody>'
                         '</mujoco>'}, SpawnResult.UNSUPPORTED_ASSETS,
     "MJCF has an <include file='other.xml'>; an entity's MJCF must be one file"),
    ({'resource_string': mesh_box('m', 'box.obj')}, SpawnResult.UNSUPPORTED_ASSETS,
     "MJCF names mesh file 'box.obj', but MJCF given as a string may name no file"),
    ({'uri': 'package://mjcf_pkg/dotdot.mjcf'}, SpawnResult.UNSUPPORTED_ASSETS,
     "MJCF mesh file '../../../../outside.obj' lies outside"),
    ({'uri': 'package://mjcf_pkg/linked.mjcf'}, SpawnResult.UNSUPPORTED_ASSETS,
     "MJCF mesh file 'link.obj' lies outside"),
    ({'uri': 'package://mjcf_pkg/absent.mjcf'}, SpawnResult.MISSING_ASSETS,
     "MJCF mesh file 'absent.obj' is not there"),
    ({'uri': 'package://mjcf_pkg/escape.xml'}, SpawnResult.NO_RESOURCE,
     "uri 'package://mjcf_pkg/escape.xml' leads outside the share folder of its package"),
    ({'uri': 'package://mjcf_pkg/../../outside.xml'}, SpawnResult.NO_RESOURCE,
     "must not contain '..'"),
    ({'uri': 'package://mjcf_pkg/huge.xml'}, SpawnResult.RESOURCE_PARSE_ERROR,
     "uri 'package://mjcf_pkg/huge.xml' is larger than the limit of 10485760 bytes"),
    ({'resource_string': '<mujoco><worldbody>'}, SpawnResult.RESOURCE_PARSE_ERROR,
     'resource_string does not parse as XML'),
    ({'resource_string': '<mujoco><worldbody><body name="a"/><body name="b"/></worldbody>'
                         '</mujoco>'}, SpawnResult.RESOURCE_PARSE_ERROR,
     "MJCF worldbody holds 2 top-level bodies ('a', 'b'); an entity is one tree: put them "
     'under one body'),
    ({'resource_string': '<mujoco><worldbody><body><geom size="1" material="none"/></body>'
                         '</worldbody></mujoco>'}, SpawnResult.RESOURCE_PARSE_ERROR,
     'MJCF does not compile'),
    ({'resource_string': '<mujoco><tendon/><worldbody><body/></worldbody></mujoco>'},
     SpawnResult.RESOURCE_PARSE_ERROR, 'MJCF section <tendon> is not supported'),
]


def test_hostile_mjcf_gets_its_code_and_changes_nothing(world, mjcf_package):
    spawn_or_fail(world, resource_string=CRATE, initial_pose=stamped(2.0, 0.0, 0.1))
    step(world, 50)
    before = snapshot(world)
    for fields, code, message in HOSTILE_MJCF:
        response = spawn(world, name='intruder', **fields)
        assert (response.result.result, response.entity_name) == (code, ''), fields
        assert message in response.result.error_message, response.result.error_message
    assert snapshot(world) == before
    assert world.models() == ['tinybot', 'crate']


def test_a_batch_spawns_mjcf_beside_urdf(world, mjcf_package):
    requests = [
        SpawnRequest(name='crate', entity_resource=Resource(resource_string=CRATE),
                     initial_pose=stamped(2.0, 0.0, 1.0)),
        SpawnRequest(entity_resource=Resource(uri='package://mjcf_pkg/arm.xml'),
                     initial_pose=stamped(-2.0, 0.0, 0.0)),
        SpawnRequest(name='r2d2', entity_resource=Resource(
            uri='package://service_tutorial/models/r2d2.urdf'),
            initial_pose=stamped(0.0, 2.0, 0.5)),
        SpawnRequest(name='pair', entity_resource=Resource(
            resource_string='<mujoco><worldbody><body/><body/></worldbody></mujoco>'))]
    response = world.call(SpawnEntities, '/spawn_entities',
                          SpawnEntities.Request(spawn_requests=requests))
    assert response.result.result == SpawnEntities.Response.ENTITIES_SPAWN_FAILED
    assert [result.result.result for result in response.results] == [
        Result.RESULT_OK, Result.RESULT_OK, Result.RESULT_OK, SpawnResult.RESOURCE_PARSE_ERROR]
    assert [result.entity_name for result in response.results] == ['crate', 'arm', 'r2d2', '']
    step(world, 1000)
    assert close(position_of(world, 'crate'), (2.0, 0.0, 0.1), 1e-3)
    assert close(position_of(world, 'arm'), (-2.0, 0.0, 0.05), 1e-3)
