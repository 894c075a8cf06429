"""
Gazebo's SDF worlds and models through the standard's own types, as a Jazzy user has them.

A package installed in tmp holds the suite's SDF world (worlds/plaza.sdf) and its model
folders (models/rover, models/pavilion), found by model:// in the installed packages' models/
folders as ros_gz users find theirs: the world is listed, loaded (its physics, its scenery, its
entities where it puts them), unloaded and loaded again; the world parameter starts with it; a
robot spawned from SDF stands where it was asked; GetSpawnables offers the model folders. The
lesson's own Gazebo Classic world loads with its missing meshes named, and tinybot's laser in
it reads its walls. Every hostile SDF file is refused with the standard's code and a message
naming the element, and the world's entities and time stay as they were.
"""

import math
import os
import shutil

import numpy as np
import pytest
from repository import install_package, LESSON_ROBOTS, TEST_MODELS
from sensor_msgs.msg import LaserScan
from simulation_interfaces.msg import Resource, Result, SpawnEntity as SpawnRequest
from simulation_interfaces.msg import SpawnResult
from simulation_interfaces.srv import GetSpawnables, LoadWorld, SpawnEntities
from simulation_interfaces.srv import StepSimulation
from standard_entities import entity_state, position_of, spawn, spawn_or_fail, stamped
from test_standard_worlds import available, current, entities, exactly, load, load_or_fail
from test_standard_worlds import OWN, state, STOPPED, unload

pytestmark = pytest.mark.ros

SDF = os.path.join(TEST_MODELS, 'sdf')
PLAZA = 'package://sdf_pkg/worlds/plaza.sdf'
GCAMP = os.path.join(LESSON_ROBOTS, 'gcamp_gazebo')
OK = Result.RESULT_OK


@pytest.fixture
def sdf_package(tmp_path, monkeypatch):
    """Install a package with the suite's SDF world and model folders; no resource path."""
    for variable in ('GZ_SIM_RESOURCE_PATH', 'IGN_GAZEBO_RESOURCE_PATH', 'GAZEBO_MODEL_PATH'):
        monkeypatch.delenv(variable, raising=False)
    share = install_package(tmp_path, monkeypatch, 'sdf_pkg')
    shutil.copytree(os.path.join(SDF, 'models'), share / 'models')
    shutil.copytree(os.path.join(SDF, 'worlds'), share / 'worlds')
    return share


@pytest.fixture
def world(ros, sdf_package):
    """Start the yard, paused, with the SDF package installed."""
    return ros.start_world(paused=True, real_time_factor=0.0)


def step(world, steps):
    """Step the paused world through the standard."""
    response = world.call(StepSimulation, '/step_simulation',
                          StepSimulation.Request(steps=steps), timeout=60.0)
    assert response.result.result == OK, response.result.error_message


def test_an_sdf_world_is_listed_loaded_unloaded_and_loaded_again(world):
    listed = {found.world_resource.uri: found for found in available(world).worlds}
    assert PLAZA in listed and listed[PLAZA].name == 'plaza'
    assert 'sdf' in listed[PLAZA].tags and 'SDF 1.8' in listed[PLAZA].description
    # The model folders beside it are no worlds: not listed, and no failure either.
    assert available(world).result.result == OK

    response = load_or_fail(world, PLAZA)
    assert response.world.name == 'plaza'
    assert state(world) == STOPPED and world.node.world.time == 0.0
    # The static pavilion is scenery; the rover (named scout by its include) and the crate
    # are entities, where the world puts them.
    assert sorted(entities(world)) == ['crate', 'scout']
    assert position_of(world, 'scout') == pytest.approx((-1.0, 0.5, 0.08))
    assert position_of(world, 'crate') == pytest.approx((0.0, -2.0, 0.5))
    # Its physics: max_step_size and gravity.
    model = world.node.world.model
    assert world.node.world.timestep == 0.004 and model.opt.timestep == 0.004
    assert model.opt.gravity == pytest.approx([0.0, 0.0, -9.5])
    # The pavilion stands on the frame 'square': 4 m along x, turned 90 degrees; its column_ne
    # (1.8, 1.3 in the pavilion's frame) at (4 - 1.3, 1.8); the ground is Fuel's Ground Plane.
    bodies = {model.body(index).name: index for index in range(model.nbody)}
    column = world.node.world.data.xpos[bodies['scenery/pavilion::column_ne']]
    assert column == pytest.approx([2.7, 1.8, 1.1])
    assert 'scenery/ground_plane::link' in bodies and 'ground_plane' not in {
        model.geom(index).name for index in range(model.ngeom)}
    # The rover's DiffDrive is simulated; the world's WindEffects system is named, not.
    assert 'gz-sim-diff-drive-system' not in response.result.error_message
    assert "<plugin> 'gz-sim-wind-effects-system' of world 'plaza'" in \
        response.result.error_message

    step(world, 250)  # one second: the crate falls on the Ground Plane, the rover stays
    assert position_of(world, 'crate') == pytest.approx((0.0, -2.0, 0.1), abs=2e-3)
    assert position_of(world, 'scout') == pytest.approx((-1.0, 0.5, 0.08), abs=2e-3)

    assert unload(world).result == OK and entities(world) == []
    load_or_fail(world, PLAZA)
    assert sorted(entities(world)) == ['crate', 'scout'] and world.node.world.time == 0.0
    # The package's own world again: its timestep is the node's parameter, its gravity Earth's.
    load_or_fail(world, OWN + 'yard.world.xml')
    assert world.node.world.timestep == 0.002
    assert world.node.world.model.opt.gravity == pytest.approx([0.0, 0.0, -9.81])


def test_the_world_parameter_starts_with_an_sdf_world(ros, sdf_package):
    plaza = ros.start_world(world='plaza', paused=True)
    assert current(plaza).world.name == 'plaza'
    assert current(plaza).world.world_resource.uri == PLAZA
    assert sorted(entities(plaza)) == ['crate', 'scout']
    assert plaza.node.world.timestep == 0.004 and plaza.node.pacer.timestep == 0.004


def test_an_installed_sdf_xacro_world_loads_with_its_default_arguments(world, sdf_package):
    (sdf_package / 'worlds' / 'hall.sdf.xacro').write_text(
        '<sdf version="1.8" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:arg name="step" default="0.005"/><world name="hall"><physics><max_step_size>'
        '$(arg step)</max_step_size></physics><include><uri>https://fuel.gazebosim.org/1.0/'
        'OpenRobotics/models/Ground Plane</uri></include><include><uri>model://rover</uri>'
        '</include></world></sdf>')
    assert 'hall' in {found.name for found in available(world).worlds}
    load_or_fail(world, 'package://sdf_pkg/worlds/hall.sdf.xacro')
    assert entities(world) == ['rover'] and world.node.world.timestep == 0.005


@pytest.mark.parametrize('fields', [
    {'uri': 'package://sdf_pkg/models/rover'},
    {'uri': 'package://sdf_pkg/models/rover/model.sdf'},
    {'uri': 'model://rover'},
    {'resource_string': 'rover.sdf'},
], ids=['model folder', 'sdf file', 'model uri', 'resource string'])
def test_a_robot_spawned_from_sdf_stands_where_it_was_asked(world, sdf_package, fields):
    if 'resource_string' in fields:  # its meshes by model://, as a text may name them
        text = (sdf_package / 'models' / 'rover' / 'model.sdf').read_text()
        fields = {'resource_string': text.replace('meshes/chassis.stl',
                                                  'model://rover/meshes/chassis.stl')}
    yaw = 1.2
    name = spawn_or_fail(world, name='robot', initial_pose=stamped(2.0, 1.0, 0.0, yaw=yaw),
                         **fields)
    assert name == 'robot'
    step(world, 500)
    response = entity_state(world, 'robot')
    pose = response.state.pose
    assert (pose.position.x, pose.position.y, pose.position.z) == pytest.approx(
        (2.0, 1.0, 0.08), abs=2e-3)
    assert (pose.orientation.z, pose.orientation.w) == pytest.approx(
        (math.sin(yaw / 2), math.cos(yaw / 2)), abs=2e-3)


def test_a_fleet_spawns_from_sdf_in_one_call(world):
    requests = [SpawnRequest(name=f'rover_{index}', entity_resource=Resource(uri='model://rover'),
                             initial_pose=stamped(float(index), 3.0, 0.0))
                for index in range(3)]
    response = world.call(SpawnEntities, '/spawn_entities',
                          SpawnEntities.Request(spawn_requests=requests), timeout=30.0)
    assert [spawned.result.result for spawned in response.results] == [OK] * 3
    assert position_of(world, 'rover_2') == pytest.approx((2.0, 3.0, 0.08))


def test_get_spawnables_offers_the_sdf_model_folders(world):
    response = world.call(GetSpawnables, '/get_spawnables', GetSpawnables.Request(),
                          timeout=30.0)
    offered = {spawnable.uri: spawnable for spawnable in response.spawnables}
    rover = offered['package://sdf_pkg/models/rover']
    assert rover.description.startswith('rover:')
    assert 'a DiffDrive system' in rover.description and 'not simulated' not in \
        rover.description
    pavilion = offered['package://sdf_pkg/models/pavilion']
    assert 'fixed to the world' in pavilion.description
    lower, upper = ((point.x, point.y, point.z) for point in pavilion.spawn_bounds.points)
    assert lower == pytest.approx((-2.0, -1.5, 0.0)) and upper == pytest.approx(
        (2.0, 1.5, 2.14))
    assert not any(uri.startswith('package://sdf_pkg/models/rover/') for uri in offered)


# --- the lesson's own world -----------------------------------------------------------------

@pytest.mark.skipif(not os.path.isdir(GCAMP), reason=f'the lesson robots are not at {GCAMP}')
def test_the_lessons_world_loads_and_tinybots_laser_reads_its_walls(ros, tmp_path, monkeypatch):
    for variable in ('GZ_SIM_RESOURCE_PATH', 'IGN_GAZEBO_RESOURCE_PATH', 'GAZEBO_MODEL_PATH'):
        monkeypatch.delenv(variable, raising=False)
    share = install_package(tmp_path, monkeypatch, 'gcamp_gazebo')
    shutil.copytree(os.path.join(GCAMP, 'worlds'), share / 'worlds')
    world = ros.start_world(real_time_factor=0.0)
    response = load_or_fail(world, 'package://gcamp_gazebo/worlds/gcamp_world.world')
    message = response.result.error_message
    # Gazebo's model database is not here: its meshes are left out and named, not fatal.
    assert 'meshes not found, left out: model://cafe_table/meshes/cafe_table.dae' in message
    assert "'Construction Cone'" in message
    assert '<state>' in message  # Gazebo Classic's saved state is not applied
    assert sorted(entities(world)) == ['ragdoll', 'ragdoll_0']
    assert world.node.world.timestep == 0.001
    # tinybot at the origin, as the lesson spawns it: straight ahead (x), the building's wall
    # Wall_15 (the building at x = 0.468554, the wall 5.8051 along it), 0.15 m thick: its near
    # face 0.075 m closer, seen from the laser 0.02 m ahead of tinybot's centre.
    spawn_or_fail(world, name='tinybot', uri='package://service_tutorial/models/tinybot.urdf',
                  initial_pose=stamped())
    world.empty('unpause_physics')  # LoadWorld leaves the world stopped
    scan = ros.receive(LaserScan, '/scan', timeout=60.0)[0]
    ranges = np.array(scan.ranges)
    ahead = round((0.0 - scan.angle_min) / scan.angle_increment)
    assert ranges[ahead] == pytest.approx(0.468554 + 5.8051 - 0.075 - 0.02, abs=0.05)
    # Behind, Wall_11, along y at x = 0.468554 - 4.16991.
    behind = 0
    assert ranges[behind] == pytest.approx(4.16991 - 0.468554 - 0.075 + 0.02, abs=0.05)
    print(f'gcamp_world: {len(entities(world))} entities, scan ahead {ranges[ahead]:.3f} m, '
          f'behind {ranges[behind]:.3f} m; LoadWorld said: {message[:300]}')


# --- bad input ---------------------------------------------------------------------------

LINK = ('<link name="base"><inertial><mass>1</mass></inertial><collision name="c"><geometry>'
        '<box><size>0.1 0.1 0.1</size></box></geometry></collision></link>')


def sdf_model(inner=LINK, name='bad'):
    """Return the SDF of one model."""
    return f'<sdf version="1.8"><model name="{name}">{inner}</model></sdf>'


def sdf_world(inner):
    """Return the SDF of a world."""
    return f'<sdf version="1.8"><world name="bad_world">{inner}</world></sdf>'


def include(uri, name=None):
    """Return an <include> of a uri."""
    return f'<include><uri>{uri}</uri>{f"<name>{name}</name>" if name else ""}</include>'


@pytest.fixture
def hostile_package(sdf_package, tmp_path):
    """Add hostile model folders and worlds to the SDF package; return its share."""
    models = sdf_package / 'models'
    outside = tmp_path / 'outside'
    outside.mkdir()
    shutil.copy(os.path.join(TEST_MODELS, 'meshes', 'box_binary.stl'), outside / 'secret.stl')
    folders = {
        'loop_a': sdf_model(include('model://loop_b')),
        'loop_b': sdf_model(include('model://loop_a')),
        'climber': sdf_model('<link name="l"><collision name="c"><geometry><mesh><uri>'
                             '../../../../outside/secret.stl</uri></mesh></geometry></collision>'
                             '</link>'),
        'linked': sdf_model('<link name="l"><collision name="c"><geometry><mesh><uri>'
                            'secret.stl</uri></mesh></geometry></collision></link>'),
        'leaf': sdf_model(),
    }
    for name, text in folders.items():
        (models / name).mkdir()
        (models / name / 'model.sdf').write_text(text)
        (models / name / 'model.config').write_text(
            '<model><name>x</name><sdf version="1.8">model.sdf</sdf></model>')
    (models / 'linked' / 'secret.stl').symlink_to(outside / 'secret.stl')
    return sdf_package


HOSTILE_MODELS = [
    ('an include cycle', sdf_model(include('model://loop_a')),
     SpawnResult.UNSUPPORTED_ASSETS, 'includes itself'),
    ('nesting 40 deep', sdf_model(''.join(f'<model name="n{i}">' for i in range(40)) + LINK
                                  + '</model>' * 40),
     SpawnResult.RESOURCE_PARSE_ERROR, 'nested more than 16 deep'),
    ('ten thousand includes', sdf_model(LINK + ''.join(include('model://leaf', f'l{i}')
                                                       for i in range(10000))),
     SpawnResult.UNSUPPORTED_ASSETS, 'more than 1000 <include>s'),
    ("'..' out of the roots", sdf_model(include('model://climber')),
     SpawnResult.UNSUPPORTED_ASSETS, '../../../../outside/secret.stl'),
    ('a link out of the roots', sdf_model(include('model://linked')),
     SpawnResult.UNSUPPORTED_ASSETS, "'secret.stl' leads outside"),
    ('a network uri', sdf_model(include('https://example.com/models/crate')),
     SpawnResult.UNSUPPORTED_ASSETS, "'https://example.com/models/crate' is on the network"),
    ('a non-finite pose', sdf_model(LINK.replace('<inertial>', '<pose>0 nan 0 0 0 0</pose>'
                                                 '<inertial>')),
     SpawnResult.RESOURCE_PARSE_ERROR, "<pose> of link 'base'"),
    ('an absurd mass', sdf_model(LINK.replace('<mass>1', '<mass>1e30')),
     SpawnResult.RESOURCE_PARSE_ERROR, "<inertial> of link 'base'"),
    ('an absurd scale', sdf_model('<link name="l"><visual name="v"><geometry><mesh><uri>'
                                  'model://rover/meshes/chassis.stl</uri><scale>1e300 1 1'
                                  '</scale></mesh></geometry></visual></link>'),
     SpawnResult.RESOURCE_PARSE_ERROR, "visual 'v' of link 'l'"),
    ('a relative_to cycle', sdf_model('<link name="a"><pose relative_to="b"/></link>'
                                      '<link name="b"><pose relative_to="a"/></link>'),
     SpawnResult.RESOURCE_PARSE_ERROR, "'a' -> 'b' -> 'a'"),
    ('an unknown frame', sdf_model('<link name="a"><pose relative_to="nowhere"/></link>'),
     SpawnResult.RESOURCE_PARSE_ERROR, "'nowhere', which is no frame"),
    ('a joint to a link that is not there', sdf_model(
        LINK + '<joint name="j" type="revolute"><parent>base</parent><child>ghost</child>'
        '</joint>'), SpawnResult.RESOURCE_PARSE_ERROR, "joint 'j'"),
    ('an include of a model that is nowhere', sdf_model(include('model://atlantis')),
     SpawnResult.MISSING_ASSETS, "no model 'atlantis'"),
]


@pytest.mark.parametrize('what, text, code, words', HOSTILE_MODELS,
                         ids=[row[0] for row in HOSTILE_MODELS])
def test_every_hostile_sdf_model_is_refused_and_nothing_changes(world, hostile_package, what,
                                                                text, code, words):
    spawn_or_fail(world, name='keeper', uri='model://rover', initial_pose=stamped(0.0, 3.0))
    step(world, 10)
    before = exactly(world)
    response = spawn(world, name='newcomer', resource_string=text, timeout=60.0)
    assert response.result.result == code, response.result.error_message
    assert words in response.result.error_message, response.result.error_message
    assert exactly(world) == before


def test_a_missing_mesh_is_left_out_and_named_and_the_robot_spawns(world):
    text = sdf_model('<link name="l"><inertial><mass>1</mass></inertial><collision name="c">'
                     '<geometry><box><size>0.2 0.2 0.2</size></box></geometry></collision>'
                     '<visual name="v"><geometry><mesh><uri>model://rover/meshes/gone.dae'
                     '</uri></mesh></geometry></visual></link>')
    response = spawn(world, name='holey', resource_string=text, initial_pose=stamped(0, 3, 1))
    assert response.result.result == OK
    assert 'gone.dae' in response.result.error_message


HOSTILE_WORLDS = [
    ('a missing model', sdf_world(include('model://atlantis')), LoadWorld.Response.MISSING_ASSETS,
     "no model 'atlantis'"),
    ('an include cycle', sdf_world(include('model://loop_a')),
     LoadWorld.Response.UNSUPPORTED_ASSETS, 'includes itself'),
    ('ten thousand includes', sdf_world(''.join(include('model://leaf', f'l{i}')
                                                for i in range(10000))),
     LoadWorld.Response.UNSUPPORTED_ASSETS, 'more than 1000 <include>s'),
    ('a network uri', sdf_world(include('https://fuel.gazebosim.org/1.0/OpenRobotics/models/'
                                        'Ambulance')),
     LoadWorld.Response.UNSUPPORTED_ASSETS, 'Ambulance'),
    ('a link out of the roots', sdf_world(include('model://linked')),
     LoadWorld.Response.UNSUPPORTED_ASSETS, "'secret.stl' leads outside"),
    ('an absurd step', sdf_world('<physics><max_step_size>5</max_step_size></physics>'),
     LoadWorld.Response.RESOURCE_PARSE_ERROR, '<max_step_size>'),
    ('a non-finite gravity', sdf_world('<gravity>0 0 nan</gravity>'),
     LoadWorld.Response.RESOURCE_PARSE_ERROR, '<gravity>'),
    ('an unknown frame', sdf_world(f'<model name="m"><pose relative_to="nowhere"/>{LINK}'
                                   '</model>'),
     LoadWorld.Response.RESOURCE_PARSE_ERROR, "'nowhere', which is no frame"),
    ('a moving model refused', sdf_world(f'<model name="m">{LINK}<joint name="j" type="ball">'
                                         '<parent>base</parent><child>ghost</child></joint>'
                                         '</model>'),
     LoadWorld.Response.RESOURCE_PARSE_ERROR, "joint 'j'"),
    ('a model, not a world', sdf_model(), LoadWorld.Response.UNSUPPORTED_FORMAT,
     'spawn it as an entity'),
]


@pytest.mark.parametrize('what, text, code, words', HOSTILE_WORLDS,
                         ids=[row[0] for row in HOSTILE_WORLDS])
def test_every_hostile_sdf_world_is_refused_and_nothing_changes(world, hostile_package, what,
                                                                text, code, words):
    world.node.world.step(5, even_if_paused=True)
    before = exactly(world)
    response = load(world, resource_string=text)
    assert response.result.result == code, response.result.error_message
    assert words in response.result.error_message, response.result.error_message
    assert "world 'yard' is kept as it was" in response.result.error_message
    assert exactly(world) == before


def test_unsupported_sdf_elements_are_refused_only_when_asked(world):
    refused = load(world, PLAZA, fail_on_unsupported_element=True)
    assert refused.result.result == LoadWorld.Response.UNSUPPORTED_ELEMENTS
    assert "<plugin> 'gz-sim-wind-effects-system' of world 'plaza'" in \
        refused.result.error_message
    assert current(world).world.name == 'yard'
