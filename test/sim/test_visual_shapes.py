"""What a viewer outside MuJoCo sees of the world: its visual shapes, colours and poses."""

import os

import mujoco
import numpy as np
import pytest
from repository import model_path, TEST_MODELS
from service_tutorial.sim import frames
from service_tutorial.sim.visual_shapes import shape_poses, visual_shapes
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

TINYBOT_BLUE = (0.16, 0.38, 0.74, 1.0)


@pytest.fixture
def world():
    world = World(scenery=model_path('yard'))
    spawn_file(world, 'tinybot', model_path('tinybot'))
    return world


def visual_geoms(world, prefix):
    """Return the ids of the visual geoms of the bodies whose names start with prefix."""
    mj_model = world.model
    return [geom for geom in range(mj_model.ngeom) if mj_model.geom_group[geom] == 1
            and mj_model.body(mj_model.geom_bodyid[geom]).name.startswith(prefix)]


def test_every_visual_shape_of_tinybot_and_the_scenery_and_no_collision_shape(world):
    shapes = visual_shapes(world)
    tinybot = [shape for shape in shapes if shape.model_name == 'tinybot']

    assert [shape.geom_id for shape in tinybot] == visual_geoms(world, 'tinybot::')
    assert len(tinybot) == 7
    assert [shape.geom_id for shape in shapes if shape.model_name == ''] == \
        visual_geoms(world, 'scenery')
    assert any(shape.rgba == pytest.approx(TINYBOT_BLUE) for shape in tinybot)
    for shape in shapes:
        assert shape.faces.max() < len(shape.vertices)


def test_a_box_is_drawn_at_its_size_and_a_mesh_with_its_own_vertices():
    world = World()
    box = ('<robot name="b"><link name="base"><inertial><mass value="1"/><inertia ixx="0.01" '
           'iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial><visual><geometry>'
           '<box size="0.4 0.2 0.1"/></geometry></visual></link></robot>')
    spawn_robot(world, 'box', box)
    spawn_file(world, 'meshbot', os.path.join(TEST_MODELS, 'meshbot.urdf'))
    shapes = visual_shapes(world)
    (box_shape,) = [shape for shape in shapes if shape.model_name == 'box']
    mesh_shapes = [shape for shape in shapes if shape.model_name == 'meshbot']
    mj_model = world.model
    meshes = [int(mj_model.geom_dataid[geom]) for geom in visual_geoms(world, 'meshbot::')
              if mj_model.geom_dataid[geom] >= 0]

    assert np.ptp(box_shape.vertices, axis=0) == pytest.approx([0.4, 0.2, 0.1])
    assert meshes
    assert sorted(len(shape.vertices) for shape in mesh_shapes) == sorted(
        int(mj_model.mesh_vertnum[mesh]) for mesh in meshes)


def test_poses_follow_a_move_without_a_step_and_match_mujoco(world):
    geom_ids = np.array(visual_geoms(world, 'tinybot::'))
    before, _ = shape_poses(world, geom_ids)
    world.set_model_state('tinybot', position=(1.0, 2.0, 0.5),
                          orientation=frames.yaw_quaternion(0.7))
    positions, orientations = shape_poses(world, geom_ids)

    # Every shape moved with the model, without a step in between, as MuJoCo places it.
    for index, geom in enumerate(geom_ids):
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, orientations[index])
        assert rotation == pytest.approx(world.data.geom_xmat[geom], abs=1e-6)
    assert positions[0] - before[0] != pytest.approx(np.zeros(3))
    assert np.linalg.norm(orientations, axis=1) == pytest.approx(np.ones(len(geom_ids)))
