"""
The standard entity services through real clients on the running world, in the standard's types.

Spawning by string and by uri, every refusal code of spawning with its message, renaming,
namespaces, poses relative to another entity, batches, both views of one world, categories and
tags, states and bounds. Physics is paused where states are compared, so "unchanged" is exact.
"""

import os

from ament_index_python.packages import get_package_share_directory
import pytest
from repository import install_package, read_model, TEST_MODELS
from simulation_interfaces.msg import EntityCategory, EntityInfo, EntityState, Resource
from simulation_interfaces.msg import Result, SpawnEntity as SpawnRequest, SpawnResult
from simulation_interfaces.srv import DeleteEntity, GetEntityBounds, GetEntityInfo
from simulation_interfaces.srv import SetEntityInfo, SetEntityState, SpawnEntities
from standard_entities import close, CRATE, entities, position_of, red_box, snapshot, spawn
from standard_entities import spawn_or_fail, stamped

pytestmark = pytest.mark.ros

SHARE = get_package_share_directory('service_tutorial')
R2D2_URI = 'package://service_tutorial/models/r2d2.urdf'
NAMELESS = '<robot><link name="a"/></robot>'


@pytest.fixture
def world(ros):
    """Start the default world, tinybot at the origin, paused so that states stay put."""
    return ros.start_world(paused=True, real_time_factor=0.0)


def test_spawn_by_string_lands_where_asked_and_the_lesson_sees_it(world):
    response = spawn(world, name='r2d2', resource_string=read_model('r2d2'),
                     initial_pose=stamped(-2.0, 1.0, 1.0, yaw=-1.5708))
    assert response.result.result == Result.RESULT_OK, response.result.error_message
    assert response.entity_name == 'r2d2'
    assert world.models() == ['tinybot', 'r2d2']
    assert close(position_of(world, 'r2d2'), (-2.0, 1.0, 1.0))


def test_spawn_by_package_uri_takes_the_name_inside_the_file(world):
    assert spawn_or_fail(world, uri=R2D2_URI, initial_pose=stamped(2.0, 0.0, 0.5)) == 'r2d2'
    assert close(position_of(world, 'r2d2'), (2.0, 0.0, 0.5))


def test_the_uri_wins_over_the_string(world):
    name = spawn_or_fail(world, uri=R2D2_URI, resource_string=CRATE,
                         initial_pose=stamped(2.0, 0.0, 0.5))
    assert name == 'r2d2'


def test_spawn_by_file_uri_inside_a_package_share(world):
    name = spawn_or_fail(world, name='artoo', uri='file://' + os.path.join(
        SHARE, 'models', 'r2d2.urdf'), initial_pose=stamped(2.0, 0.0, 0.5))
    assert name == 'artoo'
    assert 'artoo' in world.models()


@pytest.fixture
def hostile_package(tmp_path, monkeypatch):
    """Install a package with a URDF, a xacro file and a link to a file outside its share."""
    share = install_package(tmp_path, monkeypatch, 'hostile_pkg')
    outside = tmp_path / 'outside.urdf'
    outside.write_text(CRATE)
    (share / 'escape.urdf').symlink_to(outside)
    (share / 'crate.urdf').write_text(CRATE)
    crate_link = CRATE[CRATE.index('<link'):CRATE.index('</robot>')]
    (share / 'tower.urdf.xacro').write_text(
        '<robot name="tower" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:property name="side" value="0.3"/>'
        + crate_link.replace('0.4 0.4 0.4', '${side} ${side} 1.0') + '</robot>')
    return share, outside


def test_a_uri_is_read_only_from_inside_a_package_share(world, hostile_package):
    """Spawn from a package share, expanding a xacro file; refuse every way out of it."""
    share, outside = hostile_package
    assert spawn_or_fail(world, uri='package://hostile_pkg/crate.urdf',
                         initial_pose=stamped(3.0, 0.0, 0.3)) == 'crate'
    # An installed xacro file is expanded, as a launch file would expand it.
    assert spawn_or_fail(world, uri='package://hostile_pkg/tower.urdf.xacro',
                         initial_pose=stamped(-3.0, 0.0, 0.5)) == 'tower'
    tower = world.call(GetEntityBounds, '/get_entity_bounds',
                       GetEntityBounds.Request(entity='tower')).bounds.points
    assert close((tower[1].x, tower[1].y, tower[1].z), (0.15, 0.15, 0.5))
    before = snapshot(world)
    for uri, message in [
            (f'file://{outside}', 'lies outside the share folders of the installed packages'),
            ('package://hostile_pkg/escape.urdf', "uri 'package://hostile_pkg/escape.urdf' "
             'leads outside the share folder of its package'),
            (f'file://{share}/escape.urdf', 'leads outside the share folder'),
            (f'file://{share}/../../../outside.urdf', "must not contain '..'")]:
        response = spawn(world, name='intruder', uri=uri)
        assert response.result.result == SpawnResult.NO_RESOURCE, uri
        assert message in response.result.error_message
    assert snapshot(world) == before


TINYBOT_NAME_TAKEN = {'name': 'tinybot', 'resource_string': CRATE}
SPAWN_REFUSALS = [
    (TINYBOT_NAME_TAKEN, SpawnResult.NAME_NOT_UNIQUE,
     "SpawnEntity: a model named 'tinybot' already exists"),
    ({'name': 'r2/d2', 'resource_string': CRATE}, SpawnResult.NAME_INVALID,
     "SpawnEntity: model name 'r2/d2' must not contain '/'"),
    ({'name': '', 'resource_string': NAMELESS}, SpawnResult.NAME_INVALID,
     'SpawnEntity: model name must not be empty'),
    ({'name': 'x' * 300, 'resource_string': CRATE}, SpawnResult.NAME_INVALID,
     'characters) is longer than 64 characters'),
    ({'name': 'w', 'resource_string': '<sdf version="1.9"><world name="w"/></sdf>'},
     SpawnResult.UNSUPPORTED_FORMAT,
     'SpawnEntity: SDF holds a <world>, not a model to spawn: load it as a world (LoadWorld)'),
    ({'resource_string': '<sdf version="1.9"><model name="m"/></sdf>'},
     SpawnResult.RESOURCE_PARSE_ERROR,
     "SpawnEntity: model 'm' has no link; a model has at least one"),
    ({'uri': 'package://service_tutorial/package.xml'}, SpawnResult.UNSUPPORTED_FORMAT,
     "SpawnEntity: uri 'package://service_tutorial/package.xml' is neither URDF nor MJCF nor "
     'SDF: root element is <package>'),
    ({}, SpawnResult.NO_RESOURCE, 'SpawnEntity: neither uri nor resource_string is given'),
    ({'uri': 'http://example.com/r2d2.urdf'}, SpawnResult.NO_RESOURCE,
     "SpawnEntity: uri 'http://example.com/r2d2.urdf' is neither package://<package>/<path> "
     'nor file://<absolute path>'),
    ({'uri': 'package://no_such_package/r.urdf'}, SpawnResult.NO_RESOURCE,
     "SpawnEntity: uri 'package://no_such_package/r.urdf': package 'no_such_package' is not "
     'installed'),
    ({'uri': 'package://service_tutorial/../../../../etc/passwd'}, SpawnResult.NO_RESOURCE,
     "SpawnEntity: uri 'package://service_tutorial/../../../../etc/passwd' must not contain "
     "'..'"),
    ({'uri': 'file:///etc/passwd'}, SpawnResult.NO_RESOURCE,
     "SpawnEntity: uri 'file:///etc/passwd' lies outside the share folders of the installed "
     'packages'),
    ({'uri': 'package://service_tutorial/models/missing.urdf'}, SpawnResult.NO_RESOURCE,
     "SpawnEntity: uri 'package://service_tutorial/models/missing.urdf' names no file"),
    ({'name': 'crate', 'entity_namespace': '1robot', 'resource_string': CRATE},
     SpawnResult.NAMESPACE_INVALID,
     "SpawnEntity: robot namespace '1robot' is not a valid ROS namespace"),
    ({'name': 'crate', 'resource_string': '<robot name="x"><link name="a"></robot>'},
     SpawnResult.RESOURCE_PARSE_ERROR, 'SpawnEntity: resource_string does not parse as XML'),
    ({'name': 'crate',
      'resource_string': '<robot name="x" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                         '<xacro:include filename="/some/file.xacro"/><link name="a"/></robot>'},
     SpawnResult.RESOURCE_PARSE_ERROR,
     'SpawnEntity: resource_string contains xacro macros, which a spawn never expands'),
    ({'name': 'crate',
      'resource_string': '<!DOCTYPE robot SYSTEM "file:///etc/passwd"><robot name="x"/>'},
     SpawnResult.RESOURCE_PARSE_ERROR,
     'SpawnEntity: resource_string contains a DOCTYPE or ENTITY declaration, which is refused'),
    ({'name': 'crate', 'resource_string': CRATE + ' ' * (11 * 1024 * 1024)},
     SpawnResult.RESOURCE_PARSE_ERROR,
     f'SpawnEntity: resource_string is {len(CRATE) + 11 * 1024 * 1024} bytes, more than the '
     'limit of 10485760'),
    ({'name': 'crate',
      'resource_string': '<robot name="x"><link name="a"><inertial><mass value="1"/><inertia '
                         'ixx="1" iyy="1" izz="3" ixy="0" ixz="0" iyz="0"/></inertial></link>'
                         '</robot>'}, SpawnResult.RESOURCE_PARSE_ERROR,
     "SpawnEntity: model 'crate' does not compile: inertia must satisfy"),
    ({'name': 'crate', 'resource_string': CRATE, 'initial_pose': stamped(float('nan'), 0.0, 0.5)},
     SpawnResult.INVALID_POSE,
     'SpawnEntity: position contains NaN or infinity: [nan, 0.0, 0.5]'),
    ({'name': 'crate', 'resource_string': CRATE, 'initial_pose': stamped(
        0.0, 0.0, 0.5, quaternion=(0.0, 0.0, 0.0, 0.0))}, SpawnResult.INVALID_POSE,
     'SpawnEntity: orientation quaternion is zero: [0.0, 0.0, 0.0, 0.0]'),
    ({'name': 'crate', 'resource_string': CRATE, 'initial_pose': stamped(frame='nowhere')},
     SpawnResult.INVALID_POSE, "SpawnEntity: unknown reference frame 'nowhere'"),
]


def test_every_refusal_of_spawning_has_its_code_and_changes_nothing(world):
    before = snapshot(world)
    for fields, code, message in SPAWN_REFUSALS:
        response = spawn(world, **fields)
        assert (response.result.result, response.entity_name) == (code, ''), fields
        assert message in response.result.error_message, response.result.error_message
    assert snapshot(world) == before


def test_a_missing_mesh_is_left_out_and_said(world):
    urdf = read_model('missingbot', TEST_MODELS)
    response = spawn(world, name='missing', resource_string=urdf,
                     initial_pose=stamped(3.0, 0.0, 0.3))
    assert response.result.result == Result.RESULT_OK
    assert 'not found, left out' in response.result.error_message


def test_renaming_makes_a_free_name(world):
    first = spawn_or_fail(world, name='tinybot', allow_renaming=True,
                          resource_string=read_model('tinybot'), initial_pose=stamped(1.0))
    second = spawn_or_fail(world, allow_renaming=True, resource_string=read_model('tinybot'),
                           initial_pose=stamped(2.0))
    crate = spawn_or_fail(world, name='crate', allow_renaming=True, resource_string=CRATE,
                          initial_pose=stamped(3.0, 0.0, 0.3))
    assert (first, second, crate) == ('tinybot_1', 'tinybot_2', 'crate')
    assert world.models() == ['tinybot', 'tinybot_1', 'tinybot_2', 'crate']


def test_an_entity_namespace_moves_its_topics(world):
    spawn_or_fail(world, name='scout', entity_namespace='fleet/one',
                  resource_string=read_model('tinybot'), initial_pose=stamped(1.0))
    topics = world.topics()
    assert '/fleet/one/cmd_vel' in topics and '/fleet/one/odom' in topics


def test_a_pose_relative_to_another_entity(world):
    moved = world.call(SetEntityState, '/set_entity_state', SetEntityState.Request(
        entity='tinybot', state=EntityState(pose=stamped(1.0, 2.0, 0.0, yaw=1.5708).pose)))
    assert moved.result.result == Result.RESULT_OK, moved.result.error_message
    spawn_or_fail(world, name='r2d2', resource_string=read_model('r2d2'),
                  initial_pose=stamped(1.0, 0.0, 0.5, frame='tinybot'))
    assert close(position_of(world, 'r2d2'), (1.0, 3.0, 0.5), 1e-4)


def batch_request(name, urdf, x, **fields):
    """Return one SpawnEntity message of a SpawnEntities batch."""
    return SpawnRequest(name=name, entity_resource=Resource(resource_string=urdf),
                        initial_pose=stamped(x, 3.0, 0.0), **fields)


def test_a_batch_with_a_bad_request_in_the_middle(world):
    tinybot = read_model('tinybot')
    response = world.call(SpawnEntities, '/spawn_entities', SpawnEntities.Request(
        spawn_requests=[batch_request('first', tinybot, 0.0),
                        batch_request('second', tinybot, 1.0, entity_namespace='9lives'),
                        batch_request('third', tinybot, 2.0),
                        batch_request('first', tinybot, 3.0, allow_renaming=True)]))
    assert response.result.result == SpawnEntities.Response.ENTITIES_SPAWN_FAILED
    assert '1 of 4 spawn requests failed' in response.result.error_message
    assert "#1: SpawnEntities: robot namespace '9lives'" in response.result.error_message
    assert [result.result.result for result in response.results] == [
        Result.RESULT_OK, SpawnResult.NAMESPACE_INVALID, Result.RESULT_OK, Result.RESULT_OK]
    assert [result.entity_name for result in response.results] == [
        'first', '', 'third', 'first_1']
    assert world.models() == ['tinybot', 'first', 'third', 'first_1']
    assert close(position_of(world, 'third'), (2.0, 3.0, 0.0))


def test_a_batch_of_good_requests_answers_ok(world):
    response = world.call(SpawnEntities, '/spawn_entities', SpawnEntities.Request(
        spawn_requests=[batch_request(f'bot{index}', read_model('tinybot'), float(index))
                        for index in range(5)]))
    assert response.result.result == Result.RESULT_OK, response.result.error_message
    assert [result.entity_name for result in response.results] == [
        f'bot{index}' for index in range(5)]


def test_both_views_see_one_world(world):
    world.spawn_or_fail('r2d2', read_model('r2d2'), stamped(2.0, 0.0, 0.5).pose)
    assert entities(world).entities == ['tinybot', 'r2d2']
    spawn_or_fail(world, name='crate', resource_string=CRATE, initial_pose=stamped(3.0, 0, 0.3))
    assert world.models() == ['tinybot', 'r2d2', 'crate']
    deleted = world.call(DeleteEntity, '/delete_entity', DeleteEntity.Request(entity='r2d2'))
    assert deleted.result.result == Result.RESULT_OK
    assert world.models() == ['tinybot', 'crate']
    missing = world.call(DeleteEntity, '/delete_entity', DeleteEntity.Request(entity='ghost'))
    assert missing.result.result == Result.RESULT_NOT_FOUND
    assert missing.result.error_message == "DeleteEntity: no entity named 'ghost'"


def info_of(world, name):
    """Return the GetEntityInfo response of an entity."""
    return world.call(GetEntityInfo, '/get_entity_info', GetEntityInfo.Request(entity=name))


def test_categories_by_default_and_as_set(world):
    spawn_or_fail(world, name='crate', resource_string=CRATE, initial_pose=stamped(3.0, 0, 0.3))
    spawn_or_fail(world, name='red_box', resource_string=red_box(),
                  initial_pose=stamped(-3.0))
    categories = {name: info_of(world, name).info.category.category
                  for name in ('tinybot', 'crate', 'red_box')}
    assert categories == {'tinybot': EntityCategory.CATEGORY_ROBOT,
                          'crate': EntityCategory.CATEGORY_OBJECT,
                          'red_box': EntityCategory.CATEGORY_STATIC_OBJECT}
    info = EntityInfo(category=EntityCategory(category=EntityCategory.CATEGORY_DYNAMIC_OBJECT),
                      description='a crate of spare wheels', tags=['cargo', 'heavy'])
    answer = world.call(SetEntityInfo, '/set_entity_info',
                        SetEntityInfo.Request(entity='crate', info=info))
    assert answer.result.result == Result.RESULT_OK
    assert info_of(world, 'crate').info == info
    # The info goes with the entity: deleted through the lesson and spawned again, it is new.
    assert world.delete('crate').success
    world.spawn_or_fail('crate', CRATE, stamped(3.0, 0, 0.3).pose)
    assert info_of(world, 'crate').info == EntityInfo(
        category=EntityCategory(category=EntityCategory.CATEGORY_OBJECT))


def test_bad_entity_info_is_refused(world):
    before = info_of(world, 'tinybot').info
    for info, message in [
            (EntityInfo(category=EntityCategory(category=3)), 'category 3 is none of'),
            (EntityInfo(tags=['t'] * 2000), '2000 tags are more than 1000'),
            (EntityInfo(tags=['t' * 300]), 'characters) is longer than 256 characters'),
            (EntityInfo(description='d' * 20000), 'description is 20000 characters long')]:
        answer = world.call(SetEntityInfo, '/set_entity_info',
                            SetEntityInfo.Request(entity='tinybot', info=info))
        assert answer.result.result == Result.RESULT_OPERATION_FAILED
        assert message in answer.result.error_message
    assert info_of(world, 'tinybot').info == before
    assert info_of(world, 'ghost').result.result == Result.RESULT_NOT_FOUND


def test_tinybot_bounds_match_its_urdf_collision_sizes(world):
    answer = world.call(GetEntityBounds, '/get_entity_bounds',
                        GetEntityBounds.Request(entity='tinybot'))
    assert answer.result.result == Result.RESULT_OK
    assert answer.bounds.type == answer.bounds.TYPE_BOX
    lower, upper = [(point.x, point.y, point.z) for point in answer.bounds.points]
    assert close(lower, (-0.085, -0.133, 0.0)) and close(upper, (0.085, 0.133, 0.093))
