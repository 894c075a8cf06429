"""MJCF entities: they spawn, fall and rest, move by their own actuators and go without trace."""

import logging
import math
import os
import shutil

import numpy as np
import pytest
from repository import MJCF_ARM, MJCF_CRATE, read_file, TEST_MODELS, TINYBOT
from service_tutorial.sim import bounds
from service_tutorial.sim.plugins.joint_state_publisher import JointStatePublisher
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.validation import AssetError, DescriptionError, Reason
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot
from test_spawn_and_delete import contents

CRATE = read_file(MJCF_CRATE)
ARM = read_file(MJCF_ARM)
BOX_OBJ = os.path.join(TEST_MODELS, 'meshes', 'box.obj')


def run(world, seconds):
    """Step a world through seconds of simulation time."""
    world.step(round(seconds / world.timestep))


def spawn_mjcf(world, name, text, **placement):
    """Spawn an MJCF entity into a world and return its Model, or raise why not."""
    return spawn_robot(world, name, text, model_format='mjcf', **placement)


def mjcf(body, *, sections=''):
    """Return MJCF text whose worldbody holds body, with more sections before it."""
    return f'<mujoco model="m">{sections}<worldbody>{body}</worldbody></mujoco>'


def test_an_mjcf_crate_with_a_freejoint_falls_and_rests_on_the_ground():
    world = World()
    crate = spawn_mjcf(world, 'crate', CRATE, position=(0.5, 0.0, 1.0))
    assert not crate.anchored
    assert world.get_model_state('crate').position.tolist() == [0.5, 0.0, 1.0]
    run(world, 0.2)
    falling = world.get_model_state('crate')
    assert falling.position[2] < 0.9 and falling.linear_velocity[2] < -1.0
    run(world, 2.0)
    resting = world.get_model_state('crate')
    assert resting.position == pytest.approx([0.5, 0.0, 0.1], abs=1e-3)  # half its height
    assert np.abs(resting.linear_velocity).max() < 1e-3
    assert np.abs(resting.angular_velocity).max() < 1e-3
    lower, upper = bounds.box_in_base_frame(world, crate)
    assert lower == pytest.approx([-0.1] * 3) and upper == pytest.approx([0.1] * 3)


def test_an_mjcf_arm_falls_rests_reports_its_joint_and_its_own_actuator_turns_it():
    world = World()
    arm = spawn_mjcf(world, 'arm', ARM, position=(0.0, 1.0, 0.0))
    description = arm.description
    assert (description.joints, description.actuators) == (('shoulder',), ('shoulder_servo',))
    assert [type(plugin) for plugin in arm.plugins] == [JointStatePublisher]
    # Its top body's own pos places it relative to the spawn pose: 0.3 m up.
    assert world.get_model_state('arm').position.tolist() == [0.0, 1.0, 0.3]
    run(world, 2.0)
    base = world.get_model_state('arm')
    assert base.position == pytest.approx([0.0, 1.0, 0.05], abs=1e-3)
    assert np.abs(base.linear_velocity).max() < 1e-3
    names, positions, velocities = world.joint_state('arm')
    assert names == ['shoulder']
    assert abs(positions[0]) < 1e-3 and abs(velocities[0]) < 1e-3
    assert arm.plugins[0].joint_state()[0] == ['shoulder']
    world.data.ctrl[arm.actuator_index] = 0.5  # rad: the file's degrees are its own
    run(world, 2.0)
    _, positions, velocities = world.joint_state('arm')
    assert positions[0] == pytest.approx(0.5, abs=0.05) and abs(velocities[0]) < 1e-3
    # Its range of -90 to 90 degrees holds the shoulder at pi / 2.
    world.data.ctrl[arm.actuator_index] = 3.0
    run(world, 2.0)
    assert world.joint_state('arm')[1][0] == pytest.approx(math.pi / 2, abs=0.05)


def test_an_mjcf_body_without_joints_is_welded_to_the_world_and_things_rest_on_it():
    world = World()
    pillar = spawn_mjcf(world, 'pillar', mjcf(
        '<body name="pillar"><geom type="cylinder" size="0.2 0.5"/></body>'),
        position=(0.0, 0.0, 0.5))
    assert pillar.anchored and not pillar.plugins
    spawn_mjcf(world, 'crate', CRATE, position=(0.0, 0.0, 1.5))
    run(world, 2.0)
    assert world.get_model_state('pillar').position.tolist() == [0.0, 0.0, 0.5]
    assert world.get_model_state('crate').position == pytest.approx([0.0, 0.0, 1.1], abs=1e-3)


def test_an_mjcf_pendulum_hinged_to_the_world_swings_where_it_was_spawned():
    world = World()
    pendulum = spawn_mjcf(world, 'pendulum', mjcf(
        '<body><joint axis="0 1 0" damping="0.05"/>'
        '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.02" mass="0.2"/></body>'),
        position=(0.0, 0.0, 1.0))
    assert pendulum.anchored
    # Its unnamed body and joint got names, which its joint states carry.
    assert pendulum.description.root_link == 'body1'
    run(world, 0.3)
    names, positions, _ = world.joint_state('pendulum')
    assert names == ['joint1'] and positions[0] > 0.3
    assert world.get_model_state('pendulum').position.tolist() == [0.0, 0.0, 1.0]


def test_an_mjcf_entity_spawned_and_deleted_leaves_tinybot_its_state_and_no_trace():
    world, fresh = World(), World()
    for one in (world, fresh):
        spawn_file(one, 'tinybot', TINYBOT, position=(2.0, 0.0, 0.0))
    tinybot = world.models['tinybot']
    tinybot.drive().command_velocity(0.2, 0.5)
    run(world, 0.5)
    for _ in range(2):
        kept = tinybot.saved_state(world.data)
        spawn_mjcf(world, 'arm', ARM)
        spawn_mjcf(world, 'crate', CRATE, position=(0.0, 1.0, 1.0))
        for field, values in tinybot.saved_state(world.data).items():
            assert np.array_equal(values, kept[field]), field
        run(world, 0.5)
        kept = tinybot.saved_state(world.data)
        world.delete_model('arm')
        world.delete_model('crate')
        for field, values in tinybot.saved_state(world.data).items():
            assert np.array_equal(values, kept[field]), field
        assert contents(world) == contents(fresh)


def test_the_world_keeps_its_own_physics_whatever_an_mjcf_option_says():
    world = World()
    crate = spawn_mjcf(world, 'crate', CRATE.replace(
        '<worldbody>', '<option timestep="0.05" gravity="0 0 5"/><size memory="1M"/>'
        '<worldbody>'), position=(0.0, 0.0, 1.0))
    assert world.model.opt.timestep == 0.002
    assert world.model.opt.gravity.tolist() == [0.0, 0.0, -9.81]
    assert any('<option> is ignored' in note for note in crate.description.notes)
    run(world, 2.0)
    assert world.get_model_state('crate').position[2] == pytest.approx(0.1, abs=1e-3)


def test_mesh_files_are_read_from_the_mjcf_folder_and_nowhere_else(tmp_path):
    folder = tmp_path / 'model'
    (folder / 'meshes').mkdir(parents=True)
    shutil.copy(BOX_OBJ, folder / 'meshes' / 'box.obj')
    shutil.copy(BOX_OBJ, tmp_path / 'secret.obj')
    os.symlink(tmp_path / 'secret.obj', folder / 'meshes' / 'link.obj')
    (folder / 'meshes' / 'box.msh').write_bytes(b'\0' * 64)
    (folder / 'meshes' / 'garbage.obj').write_text('v 1 2\nf 7 8 9\n')
    text = mjcf('<body><freejoint/><geom type="mesh" mesh="box" mass="1"/></body>',
                sections='<compiler meshdir="meshes"/><asset><mesh file="box.obj"/></asset>')
    world = World()
    model = spawn_mjcf(world, 'boxy', text, base_dir=str(folder), position=(0.0, 0.0, 1.0))
    assert model.description.mesh_files == (str(folder / 'meshes' / 'box.obj'),)
    run(world, 1.5)
    # The mesh is 0.1 x 0.06 x 0.04 m: the box rests 0.02 m up.
    assert world.get_model_state('boxy').position == pytest.approx([0.0, 0.0, 0.02], abs=1e-3)
    before = contents(world)
    for filename, missing, message in [
            ('../../secret.obj', False, 'lies outside'),
            ('link.obj', False, 'lies outside'),
            (str(tmp_path / 'secret.obj'), False, 'lies outside'),
            ('gone.obj', True, 'is not there'),
            ('box.msh', False, 'has a format the world does not read; use one of .stl'),
            ('garbage.obj', False, "MJCF mesh file 'garbage.obj' cannot be used: not a "
                                   'readable OBJ file')]:
        with pytest.raises(AssetError, match=message) as refusal:
            spawn_mjcf(world, 'intruder', text.replace('box.obj', filename),
                       base_dir=str(folder))
        assert refusal.value.reason == (Reason.MISSING_ASSET if missing else Reason.REFUSED_ASSET)
    assert contents(world) == before


HOSTILE_MJCF = [
    ('an include', mjcf('<body/>', sections='<include file="other.xml"/>'), AssetError,
     "MJCF has an <include file='other.xml'>; an entity's MJCF must be one file"),
    ('a mesh file in text given as a string',
     mjcf('<body/>', sections='<asset><mesh file="box.stl"/></asset>'), AssetError,
     "MJCF names mesh file 'box.stl', but MJCF given as a string may name no file"),
    ('a texture file', mjcf('<body/>', sections='<asset><texture type="2d" file="t.png"/>'
                                                '</asset>'), AssetError,
     "MJCF texture file 't.png' is not read"),
    ('a skybox', mjcf('<body/>', sections='<asset><texture name="sky" type="skybox" '
                                          'builtin="gradient" width="8" height="8"/></asset>'),
     DescriptionError, "MJCF texture 'sky' is a skybox, which would change the whole world's"),
    ('a huge texture', mjcf('<body/>', sections='<asset><texture name="big" type="2d" '
                                                'builtin="checker" width="100000" '
                                                'height="100000"/></asset>'),
     DescriptionError, "MJCF texture 'big' width must be a whole number of pixels up to 1024: "
                       "'100000'"),
    ('a replicate', mjcf('<body><replicate count="1000000" offset="1 0 0"><geom size="1"/>'
                         '</replicate></body>'), DescriptionError,
     'MJCF element <replicate> is not supported'),
    ('two top bodies', mjcf('<body name="a"/><body name="b"/>'), DescriptionError,
     "MJCF worldbody holds 2 top-level bodies ('a', 'b'); an entity is one tree"),
    ('no body', mjcf(''), DescriptionError, 'MJCF worldbody holds no body'),
    ('a geom of the worldbody', mjcf('<body/><geom size="1"/>'), DescriptionError,
     'MJCF worldbody holds a <geom> of its own'),
    ('a tendon', mjcf('<body/>', sections='<tendon/>'), DescriptionError,
     'MJCF section <tendon> is not supported in a spawned entity'),
    ('a keyframe', mjcf('<body/>', sections='<keyframe/>'), DescriptionError,
     'MJCF section <keyframe> is not supported'),
    ('a contact pair', mjcf('<body/>', sections='<contact><pair geom1="a" geom2="b"/>'
                                                '</contact>'), DescriptionError,
     'MJCF <contact><pair> is not supported'),
    ('an engine plugin', mjcf('<body><plugin plugin="x"/></body>'), DescriptionError,
     'MJCF element <plugin> is not supported'),
    ('a plane', mjcf('<body><geom type="plane" size="1 1 1"/></body>'), DescriptionError,
     'MJCF has a plane, which only the world may have'),
    ('a huge geom', mjcf('<body><geom size="600"/></body>'), DescriptionError,
     "MJCF geom '#0' is 1200 m across, more than the limit of 1000 m"),
    ('what does not compile', mjcf('<body><geom size="1" material="none"/></body>'),
     DescriptionError, 'MJCF does not compile: .*material'),
    ('malformed XML', '<mujoco><worldbody>', DescriptionError, 'MJCF does not parse as XML'),
    ('an entity', '<!DOCTYPE m [<!ENTITY e "x">]><mujoco/>', DescriptionError,
     'MJCF contains a DOCTYPE or ENTITY declaration'),
    ('a huge file', mjcf('<body/>') + ' ' * (10 * 1024 * 1024), DescriptionError,
     'more than the limit of 10485760'),
    ('another root', '<robot name="r"/>', DescriptionError,
     'MJCF must have the root element <mujoco>, not <robot>'),
]


@pytest.mark.parametrize('what, text, refusal, message', HOSTILE_MJCF,
                         ids=[case[0] for case in HOSTILE_MJCF])
def test_hostile_mjcf_is_refused_naming_the_value_and_changes_nothing(what, text, refusal,
                                                                      message):
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    run(world, 0.2)
    before, kept = contents(world), world.models['tinybot'].saved_state(world.data)
    with pytest.raises(refusal, match=message.replace('(', r'\(').replace(')', r'\)')):
        spawn_mjcf(world, 'intruder', text)
    assert contents(world) == before
    for field, values in world.models['tinybot'].saved_state(world.data).items():
        assert np.array_equal(values, kept[field]), field


def test_a_urdf_joint_state_publisher_block_names_the_joints_it_publishes():
    block = ('<gazebo><plugin name="joints" filename="libgazebo_ros_joint_state_publisher.so">'
             '<joint_name>wheel_right_joint</joint_name></plugin></gazebo></robot>')
    world = World()
    tinybot = spawn_robot(world, 'tinybot', read_file(TINYBOT).replace('</robot>', block))
    publisher = tinybot.plugin(JointStatePublisher)
    run(world, 0.1)
    names, positions, velocities = publisher.joint_state()
    assert names == ['wheel_right_joint'] and positions.shape == velocities.shape == (1,)
    assert not tinybot.description.ignored_plugins
    with pytest.raises(DescriptionError, match="names joint 'caster_joint', which is not a "
                                               'moving joint of the robot'):
        spawn_robot(world, 'other', read_file(TINYBOT).replace('</robot>', block.replace(
            'wheel_right_joint', 'caster_joint')), position=(2.0, 0.0, 0.0))


def test_a_batch_mixing_mjcf_and_urdf_spawns_with_one_recompile_and_comes_to_rest():
    # Seven orders go into the world's spec in groups (attachment.GROUP_SIZE), each group
    # attached to a spec of its own first: the arms' degrees still come out as radians.
    world = World()
    orders = [SpawnOrder('tinybot', read_file(TINYBOT), position=(0.0, -2.0, 0.0))]
    for index in range(3):
        orders += [SpawnOrder(f'arm{index}', ARM, position=(index, 0.0, 0.0),
                              model_format='mjcf'),
                   SpawnOrder(f'crate{index}', CRATE, position=(index, 2.0, 1.0),
                              model_format='mjcf')]
    outcomes = world.spawn(orders)
    assert [model.name for model in outcomes] == [order.name for order in orders]
    run(world, 2.0)
    for index in range(3):
        shoulder = world.model.joint(f'arm{index}::shoulder')
        assert shoulder.range == pytest.approx([-math.pi / 2, math.pi / 2])
        assert world.get_model_state(f'arm{index}').position[2] == pytest.approx(0.05, abs=1e-3)
        assert world.get_model_state(f'crate{index}').position[2] == pytest.approx(0.1, abs=1e-3)


def test_mjcf_entities_go_back_to_their_spawn_pose_at_a_reset_and_step_without_warnings(caplog):
    world = World()
    arm = spawn_mjcf(world, 'arm', ARM, position=(0.0, 1.0, 0.0))
    spawn_mjcf(world, 'crate', CRATE, position=(0.5, 0.0, 1.0))
    spawn_mjcf(world, 'pillar', mjcf('<body><geom type="box" size="0.1 0.1 0.5"/></body>'),
               position=(-1.0, 0.0, 0.5))
    world.data.ctrl[arm.actuator_index] = 1.0
    with caplog.at_level('WARNING', logger='service_tutorial.world'):
        run(world, 2.0)
        world.set_model_state('pillar', position=(-2.0, 0.0, 0.5), orientation=(1, 0, 0, 0))
        world.reset_world()
    # The spawns' own lines are INFO, which a Jazzy install's launch plugin lets caplog keep.
    warnings = [record.getMessage() for record in caplog.records
                if record.levelno >= logging.WARNING]
    assert not warnings, warnings
    assert world.get_model_state('crate').position.tolist() == [0.5, 0.0, 1.0]
    assert world.get_model_state('arm').position.tolist() == [0.0, 1.0, 0.3]
    assert world.get_model_state('pillar').position.tolist() == [-1.0, 0.0, 0.5]
    assert world.joint_state('arm')[1].tolist() == [0.0]
