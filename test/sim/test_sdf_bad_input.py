"""
Hostile and broken SDF: each refused with its reason and a message that names the element.

Model folders are written into a resource folder of the test's own (GZ_SIM_RESOURCE_PATH):
include cycles, nesting too deep, ten thousand includes, uris that leave the roots by '..' or
by a link, network uris, numbers that are not finite or are absurd, relative_to cycles and
frames that do not exist, joints between links that do not exist, an include of a model that
is nowhere. A mesh that is not there is the one thing not refused: it is left out and named.
Every refusal leaves the world as it was: its models and its time.
"""

import os

import pytest
from repository import TEST_MODELS
from service_tutorial.sim.description_formats import FORMATS
from service_tutorial.sim.robot_files import read_path
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.validation import Reason, WorldError
from service_tutorial.sim.world import World

STL = os.path.join(TEST_MODELS, 'meshes', 'box_binary.stl')
LINK = ('<link name="base"><inertial><mass>1</mass></inertial><collision name="c"><geometry>'
        '<box><size>0.1 0.1 0.1</size></box></geometry></collision></link>')


def model(inner=LINK, name='m', version='1.8'):
    """Return the SDF of one model."""
    return f'<sdf version="{version}"><model name="{name}">{inner}</model></sdf>'


def include(uri, name=None):
    """Return an <include> of a uri."""
    named = f'<name>{name}</name>' if name else ''
    return f'<include><uri>{uri}</uri>{named}</include>'


@pytest.fixture
def models(tmp_path, monkeypatch):
    """Return a function that writes a model folder into the test's resource folder."""
    folder = tmp_path / 'models'
    folder.mkdir()
    monkeypatch.setenv('GZ_SIM_RESOURCE_PATH', str(folder))
    for variable in ('IGN_GAZEBO_RESOURCE_PATH', 'GAZEBO_MODEL_PATH'):
        monkeypatch.delenv(variable, raising=False)

    def write(name, text, config=True):
        model_folder = folder / name
        model_folder.mkdir(exist_ok=True)
        (model_folder / 'model.sdf').write_text(text)
        if config:
            (model_folder / 'model.config').write_text(
                '<model><name>x</name><sdf version="1.8">model.sdf</sdf></model>')
        return model_folder
    write.folder = folder
    return write


def world_with_a_robot():
    """Return a world with one model in it, stepped a little."""
    world = World()
    outcome, = world.spawn([SpawnOrder('keeper', model(), model_format='sdf')])
    assert not isinstance(outcome, Exception), outcome
    world.step(10)
    return world


def refusal(world, text, base_dir=None):
    """Spawn SDF text into a world; return the WorldError that refused it."""
    before = (world.model_names(), world.time, world.data.qpos.copy())
    outcome, = world.spawn([SpawnOrder('newcomer', text, model_format='sdf',
                                       base_dir=base_dir)])
    assert isinstance(outcome, WorldError), 'it spawned'
    after = (world.model_names(), world.time, world.data.qpos.copy())
    assert after[:2] == before[:2] and (after[2] == before[2]).all()
    return outcome


def test_an_include_cycle_is_refused_naming_the_files(models):
    models('a', model(include('model://b')))
    models('b', model(include('model://a')))
    error = refusal(world_with_a_robot(), model(include('model://a')))
    assert error.reason == Reason.UNSUPPORTED_CONTENT
    assert 'includes itself' in str(error) and "'model://a'" in str(error)


def test_a_model_that_includes_itself_is_refused(models):
    folder = models('selfish', model(include('model://selfish')))
    error = refusal(world_with_a_robot(), model(include('model://selfish')), str(folder))
    assert 'includes itself' in str(error)


def test_nesting_too_deep_is_refused():
    inner = LINK
    for depth in range(40):
        inner = f'<model name="level{depth}">{inner}</model>'
    error = refusal(world_with_a_robot(), model(inner))
    assert 'nested more than 16 deep' in str(error) and 'level' in str(error)


def test_ten_thousand_includes_are_refused(models):
    models('leaf', model())
    includes = ''.join(include('model://leaf', f'leaf{index}') for index in range(10000))
    error = refusal(world_with_a_robot(), model(LINK + includes))
    assert error.reason == Reason.UNSUPPORTED_CONTENT
    assert 'more than 1000 <include>s' in str(error)


@pytest.mark.parametrize('uri, words', [
    ('../../../../../../etc', 'leads outside'),
    ('/etc', 'leads outside'),
    ('file:///etc', 'leads outside'),
    ('https://example.com/models/crate', 'on the network'),
    ('http://fuel.gazebosim.org/1.0/OpenRobotics/models/Ambulance', 'on the network'),
    ('ftp://example.com/crate', 'on the network'),
    ('gopher://example.com/crate', "scheme 'gopher'"),
    ('package://no_such_package_here/models/x', 'not installed'),
    ('model://', 'names no model'),
])
def test_an_include_out_of_the_roots_or_on_the_network_is_refused(models, uri, words):
    folder = models('host', model(include(uri)))
    error = refusal(world_with_a_robot(), model(include('model://host')), str(folder))
    assert words in str(error) and '<include>' in str(error), str(error)


def test_an_include_of_a_model_that_is_nowhere_is_refused(models):
    error = refusal(world_with_a_robot(), model(LINK + include('model://atlantis')))
    assert error.reason == Reason.MISSING_ASSET
    assert "no model 'atlantis'" in str(error) and "<include> 'model://atlantis'" in str(error)


def test_a_link_that_leads_out_of_the_roots_is_refused(models, tmp_path):
    outside = tmp_path / 'outside'
    outside.mkdir()
    (outside / 'secret.stl').write_bytes(open(STL, 'rb').read())
    folder = models('linked', model(
        '<link name="l"><collision name="c"><geometry><mesh><uri>meshes/secret.stl</uri>'
        '</mesh></geometry></collision></link>'))
    (folder / 'meshes').mkdir()
    (folder / 'meshes' / 'secret.stl').symlink_to(outside / 'secret.stl')
    error = refusal(world_with_a_robot(), model(include('model://linked')))
    assert error.reason == Reason.REFUSED_ASSET
    assert 'leads outside' in str(error) and 'meshes/secret.stl' in str(error)
    # A path with '..' that leaves the model's root, likewise.
    folder = models('climber', model(
        '<link name="l"><collision name="c"><geometry><mesh><uri>../../outside/secret.stl'
        '</uri></mesh></geometry></collision></link>'))
    error = refusal(world_with_a_robot(), model(include('model://climber')))
    assert 'leads outside' in str(error) and '../../outside/secret.stl' in str(error)


def test_a_missing_mesh_is_left_out_and_named(models):
    folder = models('holey', model(
        '<link name="l"><inertial><mass>1</mass></inertial><collision name="c"><geometry><box>'
        '<size>1 1 1</size></box></geometry></collision><visual name="v"><geometry><mesh>'
        '<uri>model://holey/meshes/gone.dae</uri></mesh></geometry></visual></link>'))
    robot = read_path(str(folder))
    description = FORMATS['sdf'].load(robot.text, base_dir=robot.base_dir)
    assert description.missing_meshes == ('model://holey/meshes/gone.dae',)
    assert "mesh 'model://holey/meshes/gone.dae' cannot be had, so it is left out" in \
        description.notes[0]


BAD_NUMBERS = [
    ('<pose>nan 0 0 0 0 0</pose>', 'NaN or infinity', "link 'base'"),
    ('<pose>0 0 inf 0 0 0</pose>', 'NaN or infinity', "link 'base'"),
    ('<pose>1e9 0 0 0 0 0</pose>', 'absurd', "link 'base'"),
    ('<pose>0 0 0 1e300 0 0</pose>', 'absurd', "link 'base'"),
    ('<pose>0 0 0 0 0</pose>', 'must be 6 numbers', "link 'base'"),
    ('<inertial><mass>nan</mass></inertial>', 'NaN or infinite', '<mass>'),
    ('<inertial><mass>inf</mass></inertial>', 'NaN or infinite', '<mass>'),
    ('<inertial><mass>-1</mass></inertial>', 'must be positive', '<mass>'),
    ('<inertial><mass>1e12</mass></inertial>', 'at most 1e+09', '<mass>'),
    ('<inertial><inertia><ixx>1e20</ixx></inertia></inertial>', 'at most 1e+12', '<ixx>'),
    ('<inertial><inertia><ixx>-1</ixx></inertia></inertial>', 'not positive definite',
     "link 'base'"),
    ('<collision name="c"><geometry><mesh><uri>{stl}</uri><scale>1e9 1 1</scale></mesh>'
     '</geometry></collision>', 'absurd', '<scale>'),
    ('<collision name="c"><geometry><mesh><uri>{stl}</uri><scale>0 1 1</scale></mesh>'
     '</geometry></collision>', 'has a zero', '<scale>'),
    ('<collision name="c"><geometry><mesh><uri>{stl}</uri><scale>nan 1 1</scale></mesh>'
     '</geometry></collision>', 'NaN or infinity', '<scale>'),
    ('<collision name="c"><geometry><mesh><uri>{stl}</uri><scale>90000 1 1</scale></mesh>'
     '</geometry></collision>', 'more than the limit of 1000 m', "collision 'c'"),
    ('<collision name="c"><geometry><box><size>1 -1 1</size></box></geometry></collision>',
     'positive numbers', "collision 'c'"),
    ('<collision name="c"><geometry><sphere><radius>5000</radius></sphere></geometry>'
     '</collision>', 'more than the limit', "collision 'c'"),
]


@pytest.mark.parametrize('inside, words, element', BAD_NUMBERS)
def test_numbers_that_are_not_finite_or_are_absurd_are_refused(models, inside, words, element):
    folder = models('numbers', model(f'<link name="base">{inside.format(stl="box.stl")}</link>'))
    (folder / 'box.stl').write_bytes(open(STL, 'rb').read())
    robot = read_path(str(folder))
    error = refusal(world_with_a_robot(), robot.text, robot.base_dir)
    assert error.reason == Reason.NOT_PARSEABLE
    assert words in str(error) and element in str(error), str(error)


FRAMES = [
    ('<link name="a"><pose relative_to="b"/></link><link name="b"><pose relative_to="a"/>'
     '</link>', "'a' -> 'b' -> 'a'", 'cycle'),
    ('<frame name="f" attached_to="g"/><frame name="g" attached_to="f"/>' + LINK,
     "'f' -> 'g' -> 'f'", 'cycle'),
    ('<link name="a"><pose relative_to="nowhere"/></link>', "'nowhere'", 'no frame'),
    (LINK + '<link name="b"><pose relative_to="base::x"/></link>', "'base::x'", 'no frame'),
    (LINK + '<link name="arm"/><joint name="j" type="revolute"><parent>base</parent><child>'
     'ghost</child></joint>', "joint 'j'", "'ghost', which is no frame"),
    (LINK + '<joint name="j" type="fixed"><parent>phantom</parent><child>base</child>'
     '</joint>', "joint 'j'", "'phantom', which is no frame"),
    (LINK + '<joint name="j" type="fixed"><child>base</child></joint>', "joint 'j'",
     'has no <parent>'),
    (LINK + '<joint name="j" type="fixed"><parent>base</parent><child>world</child>'
     '</joint>', "joint 'j'", 'world as its child'),
    (LINK + '<joint name="j" type="warp"><parent>world</parent><child>base</child>'
     '</joint>', "joint 'j'", "type 'warp'"),
    (LINK + LINK, "'base'", 'two frames named'),
    ('<link name="a"/><link name="b"/>', "'a', 'b'", 'free of each other'),
    ('', "model 'm'", 'has no link'),
]


@pytest.mark.parametrize('inner, named, words', FRAMES)
def test_frames_that_cycle_or_do_not_exist_are_refused(inner, named, words):
    error = refusal(world_with_a_robot(), model(inner))
    assert named in str(error) and words in str(error), str(error)


def test_a_screw_joint_and_a_world_file_and_an_old_version_are_refused():
    world = world_with_a_robot()
    screw = refusal(world, model(LINK + '<link name="nut"/><joint name="s" type="screw">'
                                 '<parent>base</parent><child>nut</child></joint>'))
    assert screw.reason == Reason.UNSUPPORTED_CONTENT and "joint 's'" in str(screw)
    a_world = refusal(world, '<sdf version="1.8"><world name="w"/></sdf>')
    assert a_world.reason == Reason.UNSUPPORTED_FORMAT and 'LoadWorld' in str(a_world)
    for version in ('1.3', '1.12', '2.0', 'x'):
        old = refusal(world, model(version=version))
        assert version in str(old), str(old)
