"""What a viewer outside MuJoCo sees of the world: each body's visual shapes, colours and poses."""

import os

import numpy as np
import pytest
from repository import model_path, TEST_MODELS
from service_tutorial.sim import frames
from service_tutorial.sim.visual_shapes import body_poses, visual_bodies
from service_tutorial.sim.world import World

TINYBOT_BLUE = (0.16, 0.38, 0.74, 1.0)


@pytest.fixture
def world():
    world = World(scenery=model_path('yard'))
    world.spawn_urdf_file('tinybot', model_path('tinybot'))
    return world


def test_every_visual_shape_of_tinybot_and_the_scenery_and_no_collision_shape(world):
    bodies = visual_bodies(world)
    tinybot = [body for body in bodies if body.model_name == 'tinybot']
    scenery = [body for body in bodies if body.model_name == '']
    mj_model = world.model
    visual_geoms = sum(1 for geom in range(mj_model.ngeom)
                       if mj_model.geom_group[geom] == 1
                       and mj_model.body(mj_model.geom_bodyid[geom]).name.startswith('tinybot::'))

    assert sum(len(body.shapes) for body in tinybot) == visual_geoms == 7
    assert scenery and all(body.name.startswith('scenery') for body in scenery)
    assert any(shape.rgba == pytest.approx(TINYBOT_BLUE) for body in tinybot
               for shape in body.shapes)
    for body in bodies:
        for shape in body.shapes:
            assert shape.faces.max() < len(shape.vertices)


def test_a_box_is_drawn_at_its_size_and_a_mesh_with_its_own_vertices():
    world = World()
    box = ('<robot name="b"><link name="base"><inertial><mass value="1"/><inertia ixx="0.01" '
           'iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial><visual><geometry>'
           '<box size="0.4 0.2 0.1"/></geometry></visual></link></robot>')
    world.spawn_urdf('box', box)
    world.spawn_urdf_file('meshbot', os.path.join(TEST_MODELS, 'meshbot.urdf'))
    shapes = {}
    for body in visual_bodies(world):
        shapes.setdefault(body.model_name, []).extend(body.shapes)
    (box_shape,) = shapes['box']
    mesh_shapes = shapes['meshbot']

    assert np.ptp(box_shape.vertices, axis=0) == pytest.approx([0.4, 0.2, 0.1])
    mj_model = world.model
    visual_meshes = [int(mj_model.geom_dataid[geom]) for geom in range(mj_model.ngeom)
                     if mj_model.geom_group[geom] == 1 and mj_model.geom_dataid[geom] >= 0
                     and mj_model.body(mj_model.geom_bodyid[geom]).name.startswith('meshbot::')]
    assert visual_meshes
    assert sorted(len(shape.vertices) for shape in mesh_shapes) == sorted(
        int(mj_model.mesh_vertnum[mesh]) for mesh in visual_meshes)


def test_poses_follow_a_move_without_a_step(world):
    bodies = visual_bodies(world)
    root = next(body for body in bodies if body.model_name == 'tinybot')
    before, _ = body_poses(world, np.array([root.body_id]))
    world.set_model_state('tinybot', position=(1.0, 2.0, 0.5),
                          orientation=frames.yaw_quaternion(0.0))
    positions, orientations = body_poses(world, np.array([root.body_id]))

    # The body moved with the model, by the model's move, without a step in between.
    assert positions[0][:2] - before[0][:2] == pytest.approx([1.0, 2.0], abs=1e-6)
    assert np.linalg.norm(orientations[0]) == pytest.approx(1.0)
