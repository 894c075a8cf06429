"""
The standard's worlds and named poses, through the standard's own types.

A test client lists, loads, unloads and loads worlds again as a scenario runner written against
simulation_interfaces would, puts robots at the worlds' named poses, and throws hostile uris,
texts and world files at LoadWorld: each is refused with its code and the world it had stays
exactly as it was.
"""

import math
import os

from geometry_msgs.msg import PoseStamped
import mujoco
from programs import program_path
import pytest
from repository import install_package, read_model, TEST_MODELS
from simulation_interfaces.msg import Bounds, Result, SimulationState, TagsFilter
from simulation_interfaces.srv import GetAvailableWorlds, GetCurrentWorld, GetEntities
from simulation_interfaces.srv import GetEntityState, GetNamedPoseBounds, GetNamedPoses
from simulation_interfaces.srv import GetSimulationState, LoadWorld, SetSimulationState
from simulation_interfaces.srv import SpawnEntity, StepSimulation, UnloadWorld

pytestmark = pytest.mark.ros

OK = Result.RESULT_OK
OWN = 'package://service_tutorial/worlds/'
YARD, PARKING, EMPTY = (OWN + name + '.world.xml' for name in ('yard', 'parking', 'empty'))
STOPPED = SimulationState.STATE_STOPPED
NO_WORLD = SimulationState.STATE_NO_WORLD


@pytest.fixture
def world(ros):
    """Start the default world, the yard with tinybot at its start, paused."""
    return ros.start_world(paused=True)


def available(world, *, tags=(), mode=TagsFilter.FILTER_MODE_ANY, sources=(), **fields):
    """Return the GetAvailableWorlds response for a tags filter and extra sources."""
    request = GetAvailableWorlds.Request(additional_sources=list(sources), **fields)
    request.filter = TagsFilter(tags=list(tags), filter_mode=mode)
    return world.call(GetAvailableWorlds, '/get_available_worlds', request)


def load(world, uri='', resource_string='', **fields):
    """Call LoadWorld; return the response."""
    return world.call(LoadWorld, '/load_world', LoadWorld.Request(
        uri=uri, resource_string=resource_string, **fields), timeout=30.0)


def load_or_fail(world, uri='', resource_string='', **fields):
    """Load a world the test needs; fail with the world's answer if it is refused."""
    response = load(world, uri, resource_string, **fields)
    assert response.result.result == OK, response.result.error_message
    return response


def current(world):
    """Return the GetCurrentWorld response."""
    return world.call(GetCurrentWorld, '/get_current_world', GetCurrentWorld.Request())


def unload(world):
    """Call UnloadWorld; return its Result."""
    return world.call(UnloadWorld, '/unload_world', UnloadWorld.Request()).result


def state(world):
    """Return the simulation state."""
    return world.call(GetSimulationState, '/get_simulation_state',
                      GetSimulationState.Request()).state.state


def entities(world):
    """Return the names of every entity."""
    return list(world.call(GetEntities, '/get_entities', GetEntities.Request()).entities)


def named_poses(world, tags=(), mode=TagsFilter.FILTER_MODE_ANY):
    """Return the GetNamedPoses response for a tags filter."""
    request = GetNamedPoses.Request(tags=TagsFilter(tags=list(tags), filter_mode=mode))
    return world.call(GetNamedPoses, '/get_named_poses', request)


def pose_bounds(world, name):
    """Return the GetNamedPoseBounds response of a named pose."""
    return world.call(GetNamedPoseBounds, '/get_named_pose_bounds',
                      GetNamedPoseBounds.Request(name=name))


def entity_pose(world, name):
    """Return an entity's position and (x, y, z, w) orientation."""
    response = world.call(GetEntityState, '/get_entity_state',
                          GetEntityState.Request(entity=name))
    assert response.result.result == OK, response.result.error_message
    pose = response.state.pose
    return ((pose.position.x, pose.position.y, pose.position.z),
            (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w))


def spawn_at(world, name, named_pose, urdf):
    """Spawn a robot at a named pose, as a scenario runner would; return the response."""
    initial = PoseStamped()
    initial.pose = named_pose.pose
    return world.call(SpawnEntity, '/spawn_entity', SpawnEntity.Request(
        name=name, resource_string=urdf, initial_pose=initial))


def close(first, second, tolerance=1e-6):
    """Return True if two sequences of numbers agree within tolerance."""
    return all(math.isclose(a, b, abs_tol=tolerance) for a, b in zip(first, second))


def exactly(world):
    """Return what must not change when a load is refused: world, entities, states, time."""
    return (current(world).world.name, state(world), world.node.world.time,
            {name: entity_pose(world, name) for name in entities(world)})


# --- listing, loading, unloading --------------------------------------------------------------

def test_the_package_offers_the_yard_the_parking_and_the_bare_plane(world):
    response = available(world)
    assert response.result.result == OK, response.result.error_message
    found = {resource.world_resource.uri: resource for resource in response.worlds}
    assert {YARD, PARKING, EMPTY} <= set(found)
    assert found[PARKING].name == 'parking' and 'parking' in found[PARKING].tags
    assert 'wall' in found[PARKING].description
    # Tags filter, any and all; every world here is on this machine.
    assert [w.name for w in available(world, tags=['parking']).worlds] == ['parking']
    both = available(world, tags=['lesson', 'default'], mode=TagsFilter.FILTER_MODE_ALL)
    assert [w.name for w in both.worlds] == ['yard']
    either = available(world, tags=['parking', 'empty'], offline_only=True)
    assert sorted(w.name for w in either.worlds) == ['empty', 'parking']


def test_load_unload_and_load_again(world):
    assert current(world).world.name == 'yard'
    assert current(world).world.world_resource.uri == YARD
    assert world.step(25) > 0.0
    response = load_or_fail(world, PARKING)
    assert response.world.name == 'parking'
    # Stopped at time 0 with the parking world's own models, and nothing else.
    assert state(world) == STOPPED and world.node.world.time == 0.0
    assert entities(world) == ['tinybot']
    assert current(world).world.world_resource.uri == PARKING
    assert [pose.name for pose in named_poses(world).poses] == ['tinybot_start', 'parking_spot']

    assert unload(world).result == OK
    assert state(world) == NO_WORLD and entities(world) == []
    assert current(world).result.result == GetCurrentWorld.Response.NO_WORLD_LOADED
    assert unload(world).result == UnloadWorld.Response.NO_WORLD_LOADED
    assert named_poses(world).poses == []
    # Without a world nothing plays, steps or spawns, and the answers say why.
    play = world.call(SetSimulationState, '/set_simulation_state', SetSimulationState.Request(
        state=SimulationState(state=SimulationState.STATE_PLAYING))).result
    assert play.result == SetSimulationState.Response.INCORRECT_TRANSITION
    assert 'no world' in play.error_message
    world.empty('unpause_physics')
    assert state(world) == NO_WORLD
    assert world.ros.get_parameter('mujoco', 'paused').bool_value is True
    refused_play = world.ros.set_parameter('mujoco', 'paused', False)
    assert not refused_play.successful and 'no world' in refused_play.reason
    stepped = world.call(StepSimulation, '/step_simulation', StepSimulation.Request(steps=10))
    assert stepped.result.result != OK and world.node.world.time == 0.0
    refused = world.spawn('r2d2', read_model('r2d2'))
    assert not refused.success and 'no world' in refused.status_message

    load_or_fail(world, YARD)
    assert state(world) == STOPPED and entities(world) == ['tinybot']
    world.empty('unpause_physics')
    world.wait_sim(0.05)
    assert state(world) == SimulationState.STATE_PLAYING


def test_a_spawn_at_a_named_pose_lands_there(world):
    load_or_fail(world, PARKING)
    spot, = named_poses(world, tags=['goal']).poses
    assert spot.name == 'parking_spot' and 'crate' in spot.description
    assert spawn_at(world, 'parked', spot, read_model('tinybot')).result.result == OK
    position, orientation = entity_pose(world, 'parked')
    assert close(position, (2.0, 0.0, 0.0)) and close(orientation, (0.0, 0.0, 0.0, 1.0))
    bounds = pose_bounds(world, 'parking_spot').bounds
    assert bounds.type == Bounds.TYPE_BOX
    lower, upper = ((p.x, p.y, p.z) for p in bounds.points)
    assert all(low <= value <= high for low, value, high in zip(lower, position, upper))


def test_the_yard_names_tinybots_start_and_r2d2s_spawn_point(world):
    poses = {pose.name: pose for pose in named_poses(world).poses}
    assert set(poses) == {'tinybot_start', 'r2d2_spawn'}
    r2d2 = poses['r2d2_spawn']
    assert (r2d2.pose.position.x, r2d2.pose.position.y, r2d2.pose.position.z) == (-2, 1, 1)
    # Turned -90 degrees about z, as the lesson's spawn_model_client puts R2-D2.
    assert close((r2d2.pose.orientation.z, r2d2.pose.orientation.w),
                 (-math.sqrt(0.5), math.sqrt(0.5)))
    assert [pose.name for pose in named_poses(world, tags=['spawn']).poses] == ['r2d2_spawn']
    sphere = pose_bounds(world, 'r2d2_spawn').bounds
    assert sphere.type == Bounds.TYPE_SPHERE and sphere.points[0].x == -2.0
    assert spawn_at(world, 'r2d2', r2d2, read_model('r2d2')).result.result == OK
    position, _ = entity_pose(world, 'r2d2')
    assert close(position, (-2.0, 1.0, 1.0), 1e-3)


def test_named_pose_names_and_filters_of_any_size(world):
    missing = pose_bounds(world, 'nowhere' * 20000)
    assert missing.result.result == Result.RESULT_NOT_FOUND
    assert len(missing.result.error_message) < 1000 and 'tinybot_start' in \
        missing.result.error_message
    too_many = named_poses(world, tags=[f't{i}' for i in range(5000)])
    assert too_many.result.result == Result.RESULT_OPERATION_FAILED
    assert named_poses(world, tags=['x' * 100000]).poses == []


def test_a_world_and_a_scenery_load_from_text(world):
    text = ('<world name="text_world"><tag>text</tag>'
            '<scenery uri="package://service_tutorial/worlds/parking.xml"/>'
            '<named_pose name="here"><origin xyz="1 2 0"/></named_pose>'
            '<model name="bot" uri="package://service_tutorial/models/tinybot.urdf" '
            'pose="here"/></world>')
    response = load_or_fail(world, resource_string=text)
    assert response.world.name == 'text_world' and response.world.tags == ['text']
    assert entities(world) == ['bot'] and close(entity_pose(world, 'bot')[0], (1, 2, 0), 1e-3)
    mjcf = ('<mujoco><worldbody><body name="wall" pos="2 0 0.5"><geom type="box" '
            'size="0.1 1 0.5"/></body></worldbody></mujoco>')
    load_or_fail(world, resource_string=mjcf)
    assert entities(world) == [] and state(world) == STOPPED


# --- hostile input ------------------------------------------------------------------------------

@pytest.fixture
def world_package(tmp_path, monkeypatch):
    """Install a package with good and hostile world files, and a file outside its share."""
    share = install_package(tmp_path, monkeypatch, 'worlds_pkg')
    (share / 'worlds').mkdir(parents=True)
    (share / 'extra').mkdir()
    outside = tmp_path / 'outside.world.xml'
    outside.write_text('<world name="outside"/>')
    files = {
        'worlds/ok.world.xml': '<world name="ok"><tag>ok</tag><scenery uri="crates.urdf"/>'
                               '</world>',
        'worlds/crates.urdf': read_model('props/red_box', TEST_MODELS),
        'extra/more.world.xml': '<world name="more"><tag>extra</tag></world>',
        'jointed.urdf': '<robot name="door"><link name="world"/><link name="door"><collision>'
                        '<geometry><box size="1 0.1 2"/></geometry></collision></link>'
                        '<joint name="hinge" type="revolute"><parent link="world"/><child '
                        'link="door"/><limit lower="0" upper="1" effort="1" velocity="1"/>'
                        '</joint></robot>',
        'jointed.world.xml': '<world><scenery uri="jointed.urdf"/></world>',
        'malformed.world.xml': '<world name="broken"><scenery uri=',
        'gazebo.world': '<gazebo version="1.0"><world name="default"/></gazebo>',
        'odd.world.xml': '<world name="odd"><light name="sun"/><tag>odd</tag></world>',
        'escape.world.xml': '<world><model name="m" uri="../../../outside.urdf"/></world>',
        'abs.world.xml': '<world><scenery uri="file:///etc/hostname"/></world>',
        'ghost.world.xml': '<world><model name="m" uri="package://worlds_pkg/ghost.urdf"/>'
                           '</world>',
        'overlap.world.xml': '<world><model name="a" uri="package://service_tutorial/models/'
                             'tinybot.urdf"/><model name="a" uri="package://service_tutorial/'
                             'models/tinybot.urdf"/></world>',
        'entity.world.xml': '<!DOCTYPE w [<!ENTITY x "x">]><world name="&x;"/>',
    }
    for name, text in files.items():
        (share / name).write_text(text)
    (share / 'huge.world.xml').write_text('<world>' + '<tag>t</tag>' * 400000 + '</world>')
    (share / 'link.world.xml').symlink_to(outside)
    return 'package://worlds_pkg/', share


def test_other_packages_and_additional_sources_are_searched(world, world_package):
    uri, share = world_package
    names = {w.name: w for w in available(world, sources=[uri + 'extra']).worlds}
    assert {'yard', 'parking', 'empty', 'ok', 'more'} <= set(names)
    assert names['ok'].world_resource.uri == uri + 'worlds/ok.world.xml'
    load_or_fail(world, uri + 'worlds/ok.world.xml')
    assert current(world).world.name == 'ok' and entities(world) == []
    bad = available(world, sources=['/etc', 'http://x/worlds', 'file:///tmp/../etc',
                                    uri + 'nothing', 'x' * 10000])
    assert bad.result.result == Result.RESULT_OPERATION_FAILED
    assert "'/etc'" in bad.result.error_message and 'http' in bad.result.error_message
    forgiving = available(world, sources=['/etc'], continue_on_error=True)
    assert forgiving.result.result == OK and "'/etc'" in forgiving.result.error_message
    assert {'yard', 'ok'} <= {w.name for w in forgiving.worlds}


def test_a_broken_world_file_in_a_package_fails_the_default_sources(world, world_package):
    uri, share = world_package
    (share / 'worlds' / 'broken.world.xml').write_text('<world name=')
    failed = available(world)
    assert failed.result.result == GetAvailableWorlds.Response.DEFAULT_SOURCES_FAILED
    assert 'broken.world.xml' in failed.result.error_message
    forgiving = available(world, continue_on_error=True)
    assert forgiving.result.result == OK and 'broken.world.xml' in \
        forgiving.result.error_message
    assert {'yard', 'ok'} <= {w.name for w in forgiving.worlds}


HOSTILE = [
    ('http://example.com/yard.world.xml', LoadWorld.Response.NO_RESOURCE, 'neither'),
    ('package://worlds_pkg/../worlds_pkg/odd.world.xml', LoadWorld.Response.NO_RESOURCE, '..'),
    ('file:///etc/passwd', LoadWorld.Response.NO_RESOURCE, 'outside the share'),
    ('package://worlds_pkg/link.world.xml', LoadWorld.Response.NO_RESOURCE, 'leads outside'),
    ('package://worlds_pkg/none.world.xml', LoadWorld.Response.NO_RESOURCE, 'names no file'),
    ('package://no_such_pkg/a.world.xml', LoadWorld.Response.NO_RESOURCE, 'not installed'),
    ('package://worlds_pkg/huge.world.xml', LoadWorld.Response.RESOURCE_PARSE_ERROR, 'larger'),
    ('package://worlds_pkg/malformed.world.xml', LoadWorld.Response.RESOURCE_PARSE_ERROR,
     'does not parse'),
    ('package://worlds_pkg/entity.world.xml', LoadWorld.Response.RESOURCE_PARSE_ERROR,
     'DOCTYPE'),
    ('package://worlds_pkg/gazebo.world', LoadWorld.Response.UNSUPPORTED_FORMAT,
     "Gazebo Classic's <gazebo>"),
    ('package://worlds_pkg/jointed.world.xml', LoadWorld.Response.UNSUPPORTED_ASSETS,
     'moving joints'),
    ('package://worlds_pkg/escape.world.xml', LoadWorld.Response.NO_RESOURCE, '..'),
    ('package://worlds_pkg/abs.world.xml', LoadWorld.Response.NO_RESOURCE, 'outside'),
    ('package://worlds_pkg/ghost.world.xml', LoadWorld.Response.NO_RESOURCE, 'names no file'),
    ('package://worlds_pkg/overlap.world.xml', Result.RESULT_OPERATION_FAILED, "'a'"),
    ('x' * 5000, LoadWorld.Response.NO_RESOURCE, 'longer than'),
    ('', LoadWorld.Response.NO_RESOURCE, 'neither uri nor resource_string'),
]


def test_every_hostile_world_is_refused_and_the_world_stays_exactly(world, world_package):
    world.spawn_or_fail('r2d2', read_model('r2d2'))
    world.empty('pause_physics')
    before = exactly(world)
    for uri, code, named in HOSTILE:
        response = load(world, uri)
        assert response.result.result == code, (uri[:80], response.result.error_message)
        assert named in response.result.error_message, (uri[:80], response.result.error_message)
        assert "world 'yard' is kept as it was" in response.result.error_message
        assert exactly(world) == before, uri[:80]
    texts = [('<world name="t"><scenery uri="/etc/hostname"/></world>',
              LoadWorld.Response.NO_RESOURCE),
             ('<mujoco><worldbody><body><joint type="hinge"/><geom size="1"/></body>'
              '</worldbody></mujoco>', LoadWorld.Response.UNSUPPORTED_ASSETS),
             ('<mujoco><asset><mesh file="/etc/hostname"/></asset></mujoco>',
              LoadWorld.Response.UNSUPPORTED_ASSETS),
             ('<mujoco><include file="other.xml"/></mujoco>',
              LoadWorld.Response.UNSUPPORTED_ASSETS),
             ('not xml at all', LoadWorld.Response.RESOURCE_PARSE_ERROR),
             ('<world' + ' a="b"' * 10 ** 6 + '/>', LoadWorld.Response.RESOURCE_PARSE_ERROR)]
    for text, code in texts:
        response = load(world, resource_string=text)
        assert response.result.result == code, (text[:80], response.result.error_message)
        assert exactly(world) == before, text[:80]


def test_unsupported_elements_are_refused_only_when_asked(world, world_package):
    uri, _ = world_package
    refused = load(world, uri + 'odd.world.xml', fail_on_unsupported_element=True)
    assert refused.result.result == LoadWorld.Response.UNSUPPORTED_ELEMENTS
    assert '<light>' in refused.result.error_message and current(world).world.name == 'yard'
    loaded = load_or_fail(world, uri + 'odd.world.xml')
    assert '<light>' in loaded.result.error_message and current(world).world.name == 'odd'


def test_a_failed_load_from_the_no_world_state_keeps_it(world, world_package):
    assert unload(world).result == OK
    response = load(world, 'package://worlds_pkg/jointed.world.xml')
    assert response.result.result == LoadWorld.Response.UNSUPPORTED_ASSETS
    assert 'the no-world state is kept' in response.result.error_message
    assert state(world) == NO_WORLD and entities(world) == []


# --- the world parameter ----------------------------------------------------------------------

def test_the_world_parameter_chooses_the_start_up_world(ros):
    parking = ros.start_world(world='parking', paused=True)
    assert current(parking).world.name == 'parking' and entities(parking) == ['tinybot']
    assert 'parking_spot' in {pose.name for pose in named_poses(parking).poses}


def test_an_empty_world_parameter_starts_without_a_world(ros):
    bare = ros.start_world(world='')
    assert state(bare) == NO_WORLD and entities(bare) == []
    load_or_fail(bare, EMPTY)
    assert state(bare) == STOPPED and current(bare).world.name == 'empty'


def test_an_unknown_world_ends_the_program_with_one_line(start_program):
    process = start_program([program_path('mujoco_world'), '--ros-args', '-p', 'world:=atlantis'])
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 2, stderr
    assert stderr.strip().splitlines()[-1].startswith('mujoco_world: ')
    assert "no world named 'atlantis'" in stderr


def test_a_scenery_changed_on_disk_is_read_again(world, world_package):
    uri, share = world_package
    load_or_fail(world, uri + 'worlds/ok.world.xml')
    assert box_sides(world) == [pytest.approx(0.4)] * 2  # the red box: its visual, its collision
    crates = share / 'worlds' / 'crates.urdf'
    crates.write_text(crates.read_text().replace('0.4 0.4 0.4', '1.2 1.2 1.2'))
    os.utime(crates, ns=(crates.stat().st_atime_ns, crates.stat().st_mtime_ns + 10 ** 9))
    load_or_fail(world, uri + 'worlds/ok.world.xml')
    assert box_sides(world) == [pytest.approx(1.2)] * 2


def box_sides(world):
    """Return the side of every box in the world's compiled model."""
    model = world.node.world.model
    return [2.0 * model.geom_size[index, 0] for index in range(model.ngeom)
            if model.geom_type[index] == mujoco.mjtGeom.mjGEOM_BOX]
