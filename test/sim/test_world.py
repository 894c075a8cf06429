"""The world: spawning, deleting, frames, model state, resets, the diff drive and recovery."""

import copy
import logging
import math
import os

import mujoco
import numpy as np
import pytest
from repository import R2D2, read_file, TINYBOT
from service_tutorial.sim import attachment
from service_tutorial.sim import frames
from service_tutorial.sim.plugins.diff_drive import MAX_WHEEL_RIM_SPEED
from service_tutorial.sim.validation import WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot
from worlds import drive_and_stop, heading, settled_world

FACING_MINUS_Y = (0.707, 0.0, 0.0, -0.707)


def tinybot_state(world):
    """Return everything that describes tinybot's motion as one vector."""
    state = world.get_model_state('tinybot')
    _, positions, velocities = world.joint_state('tinybot')
    return np.concatenate([state.position, state.orientation, state.linear_velocity,
                           state.angular_velocity, positions, velocities])


def drive(worlds, linear_x, angular_z, seconds, period=10):
    """Command the tinybot of every world at 50 Hz, stepping the worlds in lockstep."""
    for _ in range(round(seconds / (period * worlds[0].timestep))):
        for world in worlds:
            world.models['tinybot'].drive().command_velocity(linear_x, angular_z)
            world.step(period)


@pytest.fixture
def world():
    return World()


@pytest.fixture
def tinybot_world():
    return settled_world('tinybot', TINYBOT)


def test_r2d2_dropped_from_one_metre_lands_upright_facing_minus_y(world):
    spawn_robot(world, 'r2d2', read_file(R2D2), position=(-2.0, 1.0, 1.0),
                orientation=FACING_MINUS_Y, reference_frame='world')
    world.step(1000)
    state = world.get_model_state('r2d2')
    # base_footprint rests on the floor, sunk by the contact softness only.
    assert abs(state.position[2]) < 0.01
    np.testing.assert_allclose(state.position[:2], [-2.0, 1.0], atol=0.02)
    assert heading(state.orientation) == pytest.approx(-math.pi / 2.0, abs=0.03)
    assert np.linalg.norm(state.linear_velocity) < 0.01


def test_non_unit_quaternion_is_normalised(world):
    spawn_file(world, 'r2d2', R2D2, orientation=(0.0, 0.0, 0.0, 4.0))
    orientation = world.get_model_state('r2d2').orientation
    np.testing.assert_allclose(np.abs(orientation), [0.0, 0.0, 0.0, 1.0], atol=1e-12)


def test_duplicate_name_is_refused(world):
    spawn_file(world, 'r2d2', R2D2)
    with pytest.raises(WorldError, match="a model named 'r2d2' already exists"):
        spawn_file(world, 'r2d2', R2D2, position=(3.0, 0.0, 0.0))
    assert world.model_names() == ['r2d2']


@pytest.mark.parametrize('name, message', [
    ('', 'model name must not be empty'),
    ('r2/d2', "must not contain '/'"),
    ('r2 d2', 'must not contain whitespace'),
    ('r2::d2', "must not contain '::'"),
    ('r' * 65, 'longer than 64 characters'),
    ('world', 'reserved for the world frame'),
])
def test_bad_model_names_are_refused(world, name, message):
    with pytest.raises(WorldError, match=message):
        spawn_file(world, name, R2D2)
    assert world.model_names() == []


def test_bad_poses_are_refused(world):
    for kwargs, message in [
            ({'position': (0.0, math.inf, 0.0)}, 'position contains NaN or infinity'),
            ({'orientation': (0.0, 0.0, 0.0, 0.0)}, 'orientation quaternion is zero'),
            ({'orientation': (math.nan, 0.0, 0.0, 1.0)}, 'orientation contains NaN'),
            ({'reference_frame': 'foo'}, "unknown reference frame 'foo'")]:
        with pytest.raises(WorldError, match=message):
            spawn_file(world, 'r2d2', R2D2, **kwargs)
    assert world.model_names() == []


def test_model_listing_and_delete(world):
    spawn_file(world, 'tinybot', TINYBOT)
    spawn_file(world, 'r2d2', R2D2, position=(2.0, 0.0, 0.0))
    assert world.model_names() == ['tinybot', 'r2d2']
    assert 'r2d2' in world.models and 'c3po' not in world.models
    assert [name for name, model in world.models.items() if model.drive()] == ['tinybot']
    world.delete_model('r2d2')
    assert world.model_names() == ['tinybot']
    with pytest.raises(WorldError, match="no model named 'r2d2'"):
        world.delete_model('r2d2')
    assert world.model.nbody == 1 + 7  # the world body and tinybot's seven links


def test_reference_frames(world):
    spawn_file(world, 'tinybot', TINYBOT, position=(1.0, 0.0, 0.0),
               orientation=frames.yaw_quaternion(math.pi / 2.0))
    spawn_file(world, 'r2d2', R2D2, position=(1.0, 0.0, 0.0), reference_frame='tinybot')
    in_world = world.get_model_state('r2d2', 'world')
    np.testing.assert_allclose(in_world.position, [1.0, 1.0, 0.0], atol=1e-9)
    assert heading(in_world.orientation) == pytest.approx(math.pi / 2.0)
    in_tinybot = world.get_model_state('r2d2', 'tinybot')
    np.testing.assert_allclose(in_tinybot.position, [1.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(in_tinybot.orientation, [1.0, 0.0, 0.0, 0.0], atol=1e-9)
    # tinybot's base_link sits on the wheel axle, 0.033 m above base_footprint.
    in_link = world.get_model_state('r2d2', 'tinybot::base_link')
    np.testing.assert_allclose(in_link.position, [1.0, 0.0, -0.033], atol=1e-9)
    for frame in ('foo', 'tinybot::no_such_link', 'c3po::base_link', 'tinybot::'):
        with pytest.raises(WorldError, match='unknown reference frame'):
            world.get_model_state('r2d2', frame)
    with pytest.raises(WorldError, match="no model named 'c3po'"):
        world.get_model_state('c3po')


def test_set_and_get_model_state(world):
    spawn_file(world, 'r2d2', R2D2)
    spawn_file(world, 'tinybot', TINYBOT, position=(0.0, 3.0, 0.0))
    orientation = frames.yaw_quaternion(0.6)
    world.set_model_state('r2d2', position=(3.0, 4.0, 0.5), orientation=orientation,
                          linear_velocity=(0.5, 0.0, 0.0), angular_velocity=(0.0, 0.0, 0.2))
    state = world.get_model_state('r2d2')
    np.testing.assert_allclose(state.position, [3.0, 4.0, 0.5])
    np.testing.assert_allclose(state.orientation, orientation, atol=1e-12)
    np.testing.assert_allclose(state.linear_velocity, [0.5, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(state.angular_velocity, [0.0, 0.0, 0.2], atol=1e-12)
    world.step(10)
    assert world.get_model_state('r2d2').position[0] > 3.0

    world.set_model_state('r2d2', position=(0.0, 1.0, 0.0), orientation=(1.0, 0.0, 0.0, 0.0),
                          linear_velocity=(1.0, 0.0, 0.0), reference_frame='tinybot')
    relative = world.get_model_state('r2d2', 'tinybot')
    np.testing.assert_allclose(relative.position, [0.0, 1.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(relative.linear_velocity, [1.0, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(world.get_model_state('r2d2').position, [0.0, 4.0, 0.0],
                               atol=1e-3)

    for kwargs, message in [
            ({'position': (0.0, 0.0, math.nan)}, 'position contains NaN'),
            ({'orientation': (0.0, 0.0, 0.0, 0.0)}, 'orientation quaternion is zero'),
            ({'linear_velocity': (1e9, 0.0, 0.0)}, 'must stay below'),
            ({'reference_frame': 'nowhere'}, "unknown reference frame 'nowhere'")]:
        arguments = {'position': (0.0, 0.0, 0.0), 'orientation': (1.0, 0.0, 0.0, 0.0)}
        arguments.update(kwargs)
        with pytest.raises(WorldError, match=message):
            world.set_model_state('r2d2', **arguments)
    np.testing.assert_allclose(world.get_model_state('r2d2', 'tinybot').position,
                               [0.0, 1.0, 0.0], atol=1e-9)


def test_anchored_model_moves_only_by_pose(world):
    post = ('<robot name="post"><link name="world"/><link name="pole"><inertial>'
            '<mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>'
            '</inertial><collision><geometry><box size="0.1 0.1 1"/></geometry></collision>'
            '</link><joint name="anchor" type="fixed"><parent link="world"/>'
            '<child link="pole"/><origin xyz="0 0 0.5"/></joint></robot>')
    spawn_robot(world, 'post', post, position=(2.0, 0.0, 0.0))
    world.step(100)
    np.testing.assert_allclose(world.get_model_state('post').position, [2.0, 0.0, 0.5])
    world.set_model_state('post', position=(-1.0, 0.0, 0.5), orientation=(1.0, 0.0, 0.0, 0.0))
    world.step(10)
    np.testing.assert_allclose(world.get_model_state('post').position, [-1.0, 0.0, 0.5])
    with pytest.raises(WorldError, match='anchored to the world'):
        world.set_model_state('post', position=(0.0, 0.0, 0.5), orientation=(1, 0, 0, 0),
                              linear_velocity=(1.0, 0.0, 0.0))
    world.reset_world()
    np.testing.assert_allclose(world.get_model_state('post').position, [2.0, 0.0, 0.5])


@pytest.mark.parametrize('reset, keeps_time', [('reset_world', True),
                                               ('reset_simulation', False)])
def test_resets_put_models_back_at_rest(tinybot_world, reset, keeps_time):
    world = tinybot_world
    spawn_file(world, 'r2d2', R2D2, position=(-2.0, 1.0, 1.0), orientation=FACING_MINUS_Y)
    drive([world], 0.2, 0.5, 1.0)
    time_before = world.time
    getattr(world, reset)()
    assert world.model_names() == ['tinybot', 'r2d2']
    assert world.time == pytest.approx(time_before if keeps_time else 0.0)
    r2d2 = world.get_model_state('r2d2')
    np.testing.assert_allclose(r2d2.position, [-2.0, 1.0, 1.0], atol=1e-12)
    assert heading(r2d2.orientation) == pytest.approx(-math.pi / 2.0, abs=1e-3)
    tinybot = world.get_model_state('tinybot')
    np.testing.assert_allclose(tinybot.position, [0.0, 0.0, 0.0], atol=1e-12)
    assert not np.any(world.data.qvel) and not np.any(world.data.act)
    odometry = world.models['tinybot'].drive().odometry()
    assert not np.any(odometry.position) and not np.any(odometry.linear_velocity)
    # The drive command was cleared: tinybot stays where it is.
    world.step(250)
    assert np.linalg.norm(world.get_model_state('tinybot').position[:2]) < 1e-3


def test_pause_stops_time(tinybot_world):
    world = tinybot_world
    world.models['tinybot'].drive().command_velocity(0.2, 0.0)
    world.pause()
    assert world.paused
    time, position = world.time, world.get_model_state('tinybot').position
    assert world.step(100) == 0
    assert world.time == time
    np.testing.assert_array_equal(world.get_model_state('tinybot').position, position)
    world.unpause()
    assert world.step(100) == 100
    assert world.time == pytest.approx(time + 100 * world.timestep)


@pytest.mark.parametrize('linear_x, angular_z, seconds, tolerance', [
    (0.0, 0.5, 2.0, 0.015),
    (0.2, 0.0, 2.0, 0.015),
    (0.0, 0.1, 1.0, 0.02),
    (0.0, 1.5, 5.0, 0.02),
])
@pytest.mark.parametrize('odometry_source', ['0', '1'])
def test_tinybot_turns_and_drives_as_commanded(linear_x, angular_z, seconds, tolerance,
                                               odometry_source):
    urdf = read_file(TINYBOT).replace('<odometry_source>0</odometry_source>',
                                      f'<odometry_source>{odometry_source}</odometry_source>')
    world = World()
    spawn_robot(world, 'tinybot', urdf)
    world.step(250)
    turned, travelled, odometry_turned = drive_and_stop(
        world, 'tinybot', linear_x, angular_z, seconds, rest_steps=250, odometry=True)
    odometry = world.models['tinybot'].drive().odometry()
    odometry_travelled = np.linalg.norm(odometry.position[:2])
    expected_turn, expected_travel = angular_z * seconds, linear_x * seconds
    scale_turn, scale_travel = max(abs(expected_turn), 1.0), max(expected_travel, 0.1)
    assert abs(turned - expected_turn) <= tolerance * scale_turn
    assert abs(travelled - expected_travel) <= tolerance * scale_travel
    assert abs(odometry_turned - turned) <= tolerance * scale_turn
    assert abs(odometry_travelled - travelled) <= tolerance * scale_travel


def assert_driving_forward_at(world, speed):
    odometry = world.models['tinybot'].drive().odometry()
    assert odometry.linear_velocity[0] == pytest.approx(speed, rel=0.02)


def assert_wheels_stopped(world):
    _, _, wheel_speeds = world.joint_state('tinybot')
    np.testing.assert_allclose(wheel_speeds, 0.0, atol=1e-3)


def test_command_times_out_and_the_wheels_stop(tinybot_world):
    world = tinybot_world
    world.models['tinybot'].drive().command_velocity(0.2, 0.0)
    world.step(200)
    assert_driving_forward_at(world, 0.2)
    # The command lapses at 0.5 s; the wheels then ramp down at 1 m/s^2 for 0.2 s.
    world.step(250)
    assert_wheels_stopped(world)
    assert np.linalg.norm(world.get_model_state('tinybot').linear_velocity) < 1e-3
    position = world.get_model_state('tinybot').position
    world.step(500)
    np.testing.assert_allclose(world.get_model_state('tinybot').position, position, atol=1e-4)


def test_a_new_cmd_vel_timeout_applies_to_the_command_in_force(tinybot_world):
    world = tinybot_world
    world.set_cmd_vel_timeout(0.0)  # never lapse
    world.models['tinybot'].drive().command_velocity(0.2, 0.0)
    world.step(500)  # 1 s, twice the default timeout
    assert_driving_forward_at(world, 0.2)
    # The command came 1 s ago: with a timeout of 0.6 s it lapsed, and the wheels stop now.
    world.set_cmd_vel_timeout(0.6)
    world.step(150)  # the wheels ramp down at 1 m/s^2 for 0.2 s
    assert_wheels_stopped(world)
    # A new command lasts the new timeout.
    world.models['tinybot'].drive().command_velocity(0.2, 0.0)
    world.step(250)
    assert_driving_forward_at(world, 0.2)
    world.step(250)
    assert_wheels_stopped(world)
    with pytest.raises(WorldError, match='cmd_vel_timeout must not be negative: -1.0'):
        world.set_cmd_vel_timeout(-1)


def test_diff_drive_requests_are_checked(world):
    spawn_file(world, 'r2d2', R2D2)
    assert world.models['r2d2'].drive() is None
    spawn_file(world, 'tinybot', TINYBOT, position=(2.0, 0.0, 0.0))
    with pytest.raises(WorldError, match='linear_x is NaN'):
        world.models['tinybot'].drive().command_velocity(math.nan, 0.0)
    odometry = world.models['tinybot'].drive().odometry()
    assert (odometry.odometry_frame, odometry.robot_base_frame) == ('odom', 'base_footprint')
    names, positions, velocities = world.joint_state('tinybot')
    assert names == ['wheel_left_joint', 'wheel_right_joint']
    assert positions.shape == velocities.shape == (2,)
    assert world.joint_state('r2d2')[0] == ['head_swivel']


@pytest.fixture(params=['by MuJoCo', 'by the world'])
def state_carried(request, monkeypatch):
    """Carry the state through recompiles as MuJoCo 4 does, or as the world does before 4."""
    if request.param == 'by the world':
        monkeypatch.setattr(attachment, 'RECOMPILE_KEEPS_STATE', False)
    elif not attachment.RECOMPILE_KEEPS_STATE:
        pytest.skip('MuJoCo before 4 carries positions, velocities and controls only')


def test_spawn_keeps_a_driving_robot_continuous(state_carried):
    plain, busy = World(), World()
    for world in (plain, busy):
        spawn_file(world, 'tinybot', TINYBOT)
    drive([plain, busy], 0.2, 0.4, 0.5)
    before = tinybot_state(busy)
    spawn_file(busy, 'r2d2', R2D2, position=(3.0, 3.0, 1.0))
    np.testing.assert_array_equal(tinybot_state(busy), before)
    drive([plain, busy], 0.2, 0.4, 1.0)
    np.testing.assert_allclose(tinybot_state(busy), tinybot_state(plain), rtol=0, atol=1e-9)


def test_delete_keeps_a_driving_robot_continuous(state_carried):
    plain, busy = World(), World()
    for world in (plain, busy):
        # R2-D2 comes first, so deleting it moves tinybot's place in the MuJoCo arrays.
        spawn_file(world, 'r2d2', R2D2, position=(3.0, 3.0, 0.0))
        spawn_file(world, 'tinybot', TINYBOT)
    drive([plain, busy], 0.2, -0.4, 0.5)
    before = tinybot_state(busy)
    busy.delete_model('r2d2')
    np.testing.assert_array_equal(tinybot_state(busy), before)
    drive([plain, busy], 0.2, -0.4, 1.0)
    np.testing.assert_allclose(tinybot_state(busy), tinybot_state(plain), rtol=0, atol=1e-9)


REFUSED_SPAWNS = [
    ('bad_xml', '<robot name="x"><link name="a"></robot>', 'does not parse as XML'),
    ('nan_mass', '<robot name="x"><link name="a"><inertial><mass value="nan"/></inertial>'
                 '</link></robot>', 'NaN'),
    # These two pass the loader and are refused by the MuJoCo compiler, after the robot was
    # already attached to the live spec: the world must take it out again.
    ('lopsided', '<robot name="x"><link name="a"><inertial><mass value="1"/><inertia ixx="1" '
                 'iyy="1" izz="3" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>',
     'does not compile: inertia must satisfy'),
    ('massless', '<robot name="x"><link name="a"><inertial><mass value="1"/><inertia ixx="1" '
                 'iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link><link name="b"/>'
                 '<joint name="j" type="continuous"><parent link="a"/><child link="b"/>'
                 '</joint></robot>', 'does not compile: mass and inertia of moving bodies'),
]


def test_refused_spawns_change_nothing():
    plain, busy = World(), World()
    for world in (plain, busy):
        spawn_file(world, 'tinybot', TINYBOT)
    drive([plain, busy], 0.2, 0.4, 0.3)
    model = busy.model
    sizes = (model.nbody, model.njnt, model.ngeom, model.nu, model.nmesh)
    qpos, qvel, act = busy.data.qpos.copy(), busy.data.qvel.copy(), busy.data.act.copy()
    for name, urdf, message in REFUSED_SPAWNS:
        with pytest.raises(WorldError, match=message):
            spawn_robot(busy, name, urdf)
        model = busy.model
        assert (model.nbody, model.njnt, model.ngeom, model.nu, model.nmesh) == sizes
        np.testing.assert_array_equal(busy.data.qpos, qpos)
        np.testing.assert_array_equal(busy.data.qvel, qvel)
        np.testing.assert_array_equal(busy.data.act, act)
    assert busy.model_names() == ['tinybot']
    drive([plain, busy], 0.2, 0.4, 0.5)
    np.testing.assert_array_equal(busy.data.qpos, plain.data.qpos)
    # The same names can be used once the robot is sound.
    spawn_file(busy, 'massless', R2D2, position=(3.0, 0.0, 0.0))
    assert busy.model_names() == ['tinybot', 'massless']


@pytest.mark.parametrize('poke', ['nan_velocity', 'huge_velocity', 'nan_position'])
def test_unstable_robot_is_reset_alone(poke, tmp_path, monkeypatch, caplog):
    monkeypatch.chdir(tmp_path)
    plain, broken = World(), World()
    for world in (plain, broken):
        spawn_file(world, 'tinybot', TINYBOT)
        spawn_file(world, 'r2d2', R2D2, position=(3.0, 3.0, 0.0))
    drive([plain, broken], 0.2, 0.4, 0.3)
    # Reach into the MuJoCo data behind the world's back, as a renderer or a bug could.
    data = broken.data
    free_joint = broken.model.body('r2d2::base_footprint').jntadr[0]
    qvel_address = broken.model.jnt_dofadr[free_joint]
    qpos_address = broken.model.jnt_qposadr[free_joint]
    if poke == 'nan_velocity':
        data.qvel[qvel_address + 2] = math.nan
    elif poke == 'huge_velocity':
        data.qvel[qvel_address] = 1e12
    else:
        data.qpos[qpos_address + 2] = math.nan
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        caplog.clear()  # the spawns' INFO lines are kept where the root logs INFO (launch)
        drive([plain, broken], 0.2, 0.4, 0.3)
    assert np.isfinite(broken.data.qpos).all() and np.isfinite(broken.data.qvel).all()
    assert "model 'r2d2'" in caplog.text and "model 'tinybot'" not in caplog.text
    r2d2 = broken.get_model_state('r2d2')
    np.testing.assert_allclose(r2d2.position, [3.0, 3.0, 0.0], atol=0.005)
    np.testing.assert_allclose(tinybot_state(broken), tinybot_state(plain), rtol=0, atol=1e-9)
    assert broken.model_names() == ['tinybot', 'r2d2']
    assert not os.path.exists(tmp_path / 'MUJOCO_LOG.TXT')


def test_mujoco_warnings_go_to_logging(tmp_path, monkeypatch, caplog):
    monkeypatch.chdir(tmp_path)
    world = World()
    spawn_file(world, 'r2d2', R2D2)
    world.data.qvel[0] = math.inf
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        world.step(5)
    assert 'MuJoCo: Nan, Inf or huge value' in caplog.text
    assert os.listdir(tmp_path) == []


def test_step_count_and_world_settings():
    world = World(timestep=0.001, gravity=(0.0, 0.0, -1.62))
    assert world.timestep == 0.001
    np.testing.assert_allclose(world.model.opt.gravity, [0.0, 0.0, -1.62])
    assert world.step(7) == 7 and world.time == pytest.approx(0.007)
    with pytest.raises(WorldError, match='step count must not be negative'):
        world.step(-1)
    with pytest.raises(WorldError, match='timestep must be positive'):
        World(timestep=0.0)


def test_spawned_models_step_exactly_as_bare_mujoco_steps(tinybot_world):
    # How long spawning and stepping take is the benchmark's business (its core table).
    world = tinybot_world
    for index in range(5):
        spawn_file(world, f'r2d2_{index}', R2D2, position=(2.0 + index, 0.0, 0.0))
    assert world.model_names() == ['tinybot'] + [f'r2d2_{index}' for index in range(5)]

    model, data = world.model, world.data
    raw = copy.copy(data)  # bare MuJoCo from the same state
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(model, kind))
    raw_state = np.empty_like(state)
    for _ in range(3):
        assert world.step(1000) == 1000
        mujoco.mj_step(model, raw, 1000)
        mujoco.mj_getState(model, data, state, kind)
        mujoco.mj_getState(model, raw, raw_state, kind)
        np.testing.assert_array_equal(state, raw_state)


def block_robot(mass, size):
    """Return a 5 kg base with a block of the given mass and size on a hinge."""
    return ('<robot name="block"><link name="base"><inertial><mass value="5"/><inertia ixx="0.1" '
            'iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>'
            '<box size="0.3 0.3 0.1"/></geometry></collision></link><link name="block">'
            f'<inertial><mass value="{mass}"/><inertia ixx="{mass}" iyy="{mass}" izz="{mass}" '
            'ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>'
            f'<box size="{size} {size} {size}"/></geometry></collision></link>'
            '<joint name="hinge" type="continuous"><parent link="base"/><child link="block"/>'
            '<origin xyz="0.2 0 0"/><axis xyz="0 1 0"/></joint></robot>')


@pytest.mark.parametrize('label, urdf', [
    # No step of a 1e300 kg block can be computed, even at rest.
    ('heavy', block_robot('1e300', '0.1')),
    # A block a kilometre wide, the largest shape the world takes, swallows tinybot and the
    # floor.
    ('huge', block_robot('1', '1000')),
])
def test_robot_unstable_at_its_spawn_pose_is_removed_and_the_others_go_on(label, urdf, caplog):
    plain, broken = World(), World()
    for world in (plain, broken):
        spawn_file(world, 'tinybot', TINYBOT)
    drive([plain, broken], 0.2, 0.4, 0.2)
    spawn_robot(broken, 'block', urdf, position=(2.0, 0.0, 0.3))
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        caplog.clear()  # the spawns' INFO lines are kept where the root logs INFO (launch)
        drive([plain, broken], 0.2, 0.4, 0.3)
    assert broken.model_names() == ['tinybot']
    (removal,) = broken.take_removed_models()
    assert broken.take_removed_models() == []
    assert (removal.name, removal.reason) == (
        'block', 'became unstable again after it was put back at its spawn pose')
    assert 0.2 - 1e-9 <= removal.time <= broken.time  # after its spawn, before now
    messages = [record.getMessage() for record in caplog.records
                if record.name == 'service_tutorial.world' and 'MuJoCo' not in record.message]
    assert messages == [
        "model 'block' became unstable; it is put back to its spawn pose at rest",
        "model 'block' became unstable again after it was put back at its spawn pose; it is "
        'removed from the world']
    # tinybot went through every retaken step as if the block had never been there.
    np.testing.assert_allclose(tinybot_state(broken), tinybot_state(plain), rtol=0, atol=1e-9)
    spawn_file(broken, 'block', R2D2, position=(2.0, 0.0, 0.0))
    assert broken.model_names() == ['tinybot', 'block']


def test_robot_made_unstable_from_outside_gets_one_reset_per_placement(caplog):
    world = World()
    chain = ('<robot name="chain">' + ''.join(
        f'<link name="l{i}"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" '
        'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>'
        '<box size="0.1 0.1 0.1"/></geometry></collision></link>' for i in range(4)) + ''.join(
        f'<joint name="j{i}" type="continuous"><parent link="l{i - 1}"/><child link="l{i}"/>'
        '<origin xyz="0 0.12 0" rpy="0.3 0.2 0.1"/><axis xyz="1 0 0"/></joint>'
        for i in range(1, 4)) + '</robot>')
    spawn_robot(world, 'chain', chain, position=(0.0, 0.0, 0.5))
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        for _ in range(2):
            # A spin the physics cannot follow, yet below the velocity limit.
            world.set_model_state('chain', position=(0.0, 0.0, 0.5),
                                  orientation=(1.0, 0.0, 0.0, 0.0),
                                  angular_velocity=(9e4, 9e4, 0.0))
            world.step(200)
            assert world.model_names() == ['chain']
            np.testing.assert_allclose(world.get_model_state('chain').position[:2], [0.0, 0.0],
                                       atol=0.3)
    assert caplog.text.count("model 'chain' became unstable; it is put back") == 2
    assert 'removed' not in caplog.text


@pytest.mark.parametrize('linear_x, angular_z', [
    (1e300, 0.0), (1.7e308, 1.7e308), (-1e308, 1e308), (0.0, -1e300), (40.0, 3.0)])
def test_absurd_drive_commands_are_scaled_to_the_rim_speed_limit(linear_x, angular_z):
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    config = world.models['tinybot'].drive().config
    applied_x, applied_z = world.models['tinybot'].drive().command_velocity(linear_x, angular_z)
    rim_speeds = (applied_x - applied_z * config.wheel_separation / 2.0,
                  applied_x + applied_z * config.wheel_separation / 2.0)
    assert max(abs(speed) for speed in rim_speeds) == pytest.approx(MAX_WHEEL_RIM_SPEED)
    # The turn keeps its direction and, unless the numbers are absurd, its radius.
    assert math.copysign(1.0, applied_x) == math.copysign(1.0, linear_x)
    if max(abs(linear_x), abs(angular_z)) < 1e6:
        assert applied_x / applied_z == pytest.approx(linear_x / angular_z)
    world.step(500)
    assert world.model_names() == ['tinybot']
    assert np.isfinite(world.data.qvel).all()
    assert np.abs(world.joint_state('tinybot')[2]).max() <= (
        MAX_WHEEL_RIM_SPEED / config.wheel_radius * 1.01)


def test_pose_limits_and_extreme_quaternions(world):
    with pytest.raises(WorldError, match=r'position must stay below 1e\+08 m in magnitude: '
                                         r'\[1e\+300, 0.0, 0.0\]'):
        spawn_file(world, 'r2d2', R2D2, position=(1e300, 0.0, 0.0))
    spawn_file(world, 'r2d2', R2D2, orientation=(1e300, 0.0, 0.0, 1e300))
    np.testing.assert_allclose(world.get_model_state('r2d2').orientation,
                               [math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5)], atol=1e-12)
    world.set_model_state('r2d2', position=(0.0, 0.0, 0.0), orientation=(0.0, 0.0, 0.0, 1e-300))
    np.testing.assert_allclose(world.get_model_state('r2d2').orientation, [0, 0, 0, 1],
                               atol=1e-12)


def pile(count):
    """Return a robot of count boxes on hinges, all in one place: thousands of contacts."""
    # Links of one robot collide with each other only if they say so, as in Gazebo.
    links = ''.join(
        f'<link name="b{index}"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" '
        'izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>'
        '<box size="0.3 0.3 0.3"/></geometry></collision></link>'
        f'<gazebo reference="b{index}"><selfCollide>true</selfCollide></gazebo>'
        for index in range(count))
    joints = ''.join(
        f'<joint name="j{index}" type="continuous"><parent link="b0"/>'
        f'<child link="b{index}"/><origin xyz="0 0 {0.001 * index}"/></joint>'
        for index in range(1, count))
    return f'<robot name="pile">{links}{joints}</robot>'


def test_contacts_beyond_mujocos_memory_refuse_a_spawn_or_reset_the_robot(caplog):
    plain, crowded = World(), World()
    for world in (plain, crowded):
        spawn_file(world, 'tinybot', TINYBOT)
    drive([plain, crowded], 0.2, 0.4, 0.1)
    before = tinybot_state(crowded)
    with pytest.raises(WorldError, match=r"model 'heap' cannot be simulated at \[2.0, 0.0, 0.5\]"
                                         r': mj_stackAlloc: out of memory'):
        spawn_robot(crowded, 'heap', pile(80), position=(2.0, 0.0, 0.5))
    assert crowded.model_names() == ['tinybot']
    np.testing.assert_array_equal(tinybot_state(crowded), before)

    spawn_robot(crowded, 'a', pile(40), position=(2.0, 0.0, 0.5))
    spawn_robot(crowded, 'b', pile(40), position=(-2.0, 0.0, 0.5))
    drive([plain, crowded], 0.2, 0.4, 0.1)
    # Two piles in one place: MuJoCo runs out of memory for their contacts within a step.
    crowded.set_model_state('b', position=(2.0, 0.0, 0.5), orientation=(1.0, 0.0, 0.0, 0.0))
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        drive([plain, crowded], 0.2, 0.4, 0.2)
    assert 'MuJoCo: mj_stackAlloc: out of memory' in caplog.text
    assert "model 'b' became unstable; it is put back to its spawn pose" in caplog.text
    assert crowded.model_names() == ['tinybot', 'a', 'b']
    np.testing.assert_allclose(crowded.get_model_state('b').position[:2], [-2.0, 0.0],
                               atol=1e-3)
    np.testing.assert_allclose(tinybot_state(crowded), tinybot_state(plain), rtol=0, atol=1e-9)
