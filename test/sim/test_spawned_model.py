"""A spawned Model: found again by name after every recompile, its state, its plugins."""

import numpy as np
import pytest
from repository import R2D2, TINYBOT
from service_tutorial.sim.plugins.diff_drive import DiffDrive
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file


def assert_bound(world, model):
    """Check every index a Model holds against MuJoCo's named access to the world's model."""
    mj_model = world.model
    assert model.root_id == mj_model.body(model.scoped(model.description.root_link)).id
    for index, joint_name in enumerate(model.description.joints):
        joint = mj_model.joint(model.scoped(joint_name))
        assert model.joint_qpos_adr[index] == joint.qposadr[0]
        assert model.joint_dof_adr[index] == joint.dofadr[0]
    free_joint = mj_model.body(model.scoped(model.description.root_link)).jntadr[0]
    assert model.free_qpos_adr == mj_model.jnt_qposadr[free_joint]
    assert model.free_dof_adr == mj_model.jnt_dofadr[free_joint]
    bodies = {mj_model.body(model.scoped(link)).id for link in model.description.links}
    assert set(model.qpos_index) == {
        address for joint in range(mj_model.njnt) if mj_model.jnt_bodyid[joint] in bodies
        for address in range(mj_model.jnt_qposadr[joint],
                             mj_model.jnt_qposadr[joint] + (7 if joint == free_joint else 1))}
    actuators = [mj_model.actuator(model.scoped(name)).id for name in model.description.actuators]
    np.testing.assert_array_equal(model.actuator_index, actuators)
    np.testing.assert_array_equal(model.act_index, mj_model.actuator_actadr[actuators])


def test_a_model_is_found_again_by_name_after_every_recompile():
    world = World()
    spawn_file(world, 'r2d2', R2D2, position=(3.0, 0.0, 0.0))
    spawn_file(world, 'tinybot', TINYBOT)
    tinybot = world.models['tinybot']
    assert_bound(world, tinybot)
    assert tinybot.description.actuators == ('wheel_left_joint_drive',
                                             'wheel_right_joint_drive')
    before = (tinybot.root_id, tinybot.free_qpos_adr, tinybot.joint_qpos_adr.copy())
    # R2-D2 came first: deleting it moves tinybot's place in every MuJoCo array.
    world.delete_model('r2d2')
    assert world.models['tinybot'] is tinybot
    assert (tinybot.root_id, tinybot.free_qpos_adr) != before[:2]
    assert not np.array_equal(tinybot.joint_qpos_adr, before[2])
    assert_bound(world, tinybot)
    spawn_file(world, 'r2d2', R2D2, position=(3.0, 0.0, 0.0))
    assert_bound(world, tinybot)
    assert_bound(world, world.models['r2d2'])


def test_models_mapping_is_read_only_and_holds_the_plugins():
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    spawn_file(world, 'r2d2', R2D2, position=(3.0, 0.0, 0.0))
    assert list(world.models) == ['tinybot', 'r2d2']
    with pytest.raises(TypeError):
        world.models['c3po'] = world.models['r2d2']
    drive = world.models['tinybot'].plugins[0]  # then its laser, camera and IMU
    assert isinstance(drive, DiffDrive)
    assert drive.config == world.models['tinybot'].drive().config
    assert drive.block.filename == 'libgazebo_ros_diff_drive.so'
    assert drive.model is world.models['tinybot'] and drive.world is world
    assert world.models['r2d2'].plugins == ()


def test_saved_state_is_written_back_where_the_model_now_is():
    world = World()
    spawn_file(world, 'r2d2', R2D2, position=(3.0, 0.0, 0.0))
    spawn_file(world, 'tinybot', TINYBOT)
    world.models['tinybot'].drive().command_velocity(0.2, 0.5)
    world.step(100)
    tinybot = world.models['tinybot']
    saved = tinybot.saved_state(world.data)
    qpos = world.data.qpos[tinybot.qpos_index].copy()
    world.delete_model('r2d2')
    np.testing.assert_array_equal(world.data.qpos[tinybot.qpos_index], qpos)
    world.data.qpos[tinybot.qpos_index] = 0.0
    tinybot.restore_state(world.data, saved)
    np.testing.assert_array_equal(world.data.qpos[tinybot.qpos_index], qpos)
    np.testing.assert_array_equal(world.data.act[tinybot.act_index], saved['act'])
