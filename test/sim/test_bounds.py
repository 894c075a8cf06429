"""Collision geometry as oriented boxes, and its overlap with spheres, boxes and hulls."""

import numpy as np
import pytest
from repository import MODELS, read_model, TEST_MODELS, TINYBOT
from service_tutorial.sim import bounds
from service_tutorial.sim.bounds import OrientedBoxes
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot


def one_box(centre, rotation, half_sizes):
    """Return OrientedBoxes holding one box."""
    return OrientedBoxes(centres=np.array([centre], float),
                         rotations=np.array([rotation], float),
                         half_sizes=np.array([half_sizes], float))


def yaw_matrix(angle):
    """Return the rotation matrix of a turn about z."""
    cos, sin = np.cos(angle), np.sin(angle)
    return [[cos, -sin, 0.0], [sin, cos, 0.0], [0.0, 0.0, 1.0]]


def test_tinybot_bounds_are_its_urdf_collision_sizes_in_its_base_frame():
    world = World()
    spawn_file(world, 'tinybot', TINYBOT, position=(1.0, 2.0, 0.0),
               orientation=(np.cos(0.4), 0.0, 0.0, np.sin(0.4)))
    lower, upper = bounds.box_in_base_frame(world, world.models['tinybot'])
    # Chassis cylinder r 0.085 from z 0.043 to 0.093; wheels r 0.033 at y +-0.1, z 0.033.
    assert np.allclose(lower, (-0.085, -0.133, 0.0), atol=1e-6)
    assert np.allclose(upper, (0.085, 0.133, 0.093), atol=1e-6)


@pytest.mark.parametrize('name, folder', [('tinybot', MODELS), ('r2d2', MODELS),
                                          ('pairbot_ros2', TEST_MODELS)])
def test_a_description_compiled_alone_has_the_box_its_spawn_has(name, folder):
    """The box GetSpawnables offers is the one GetEntityBounds gives once spawned."""
    urdf = read_model(name, folder)
    world = World()
    spawn_robot(world, 'other', read_model('r2d2'), position=(4.0, 0.0, 0.0))
    model_before = world.model
    lower, upper = bounds.description_box(load_urdf(urdf))
    assert world.model is model_before and list(world.models) == ['other']
    spawn_robot(world, name, urdf, position=(1.0, -2.0, 0.3),
                orientation=(np.cos(0.3), 0.0, 0.0, np.sin(0.3)))
    spawned_lower, spawned_upper = bounds.box_in_base_frame(world, world.models[name])
    assert np.allclose(lower, spawned_lower, atol=1e-9)
    assert np.allclose(upper, spawned_upper, atol=1e-9)


def test_the_boxes_of_a_model_follow_it():
    world = World()
    spawn_file(world, 'tinybot', TINYBOT, position=(3.0, 0.0, 0.0))
    boxes = bounds.collision_boxes(world, world.models['tinybot'])
    assert len(boxes) == 4  # chassis, two wheels, caster
    assert bounds.overlaps_sphere(boxes, (3.0, 0.0, 0.05), 0.01)
    assert not bounds.overlaps_sphere(boxes, (0.0, 0.0, 0.05), 1.0)


def test_sphere_overlap_is_the_closest_point_of_a_turned_box():
    box = one_box((0.0, 0.0, 0.0), yaw_matrix(np.pi / 4), (1.0, 1.0, 1.0))
    corner = np.sqrt(2.0)  # the box's corner along x after the turn
    assert bounds.overlaps_sphere(box, (corner + 0.4, 0.0, 0.0), 0.5)
    assert not bounds.overlaps_sphere(box, (corner + 0.6, 0.0, 0.0), 0.5)


def test_box_overlap_by_separating_axes():
    box = one_box((0.0, 0.0, 0.0), yaw_matrix(np.pi / 4), (1.0, 1.0, 1.0))
    corner = np.sqrt(2.0)
    assert bounds.overlaps_box(box, (corner - 0.1, -0.1, -0.1), (corner + 1.0, 0.1, 0.1))
    assert not bounds.overlaps_box(box, (corner + 0.1, -0.1, -0.1), (corner + 1.0, 0.1, 0.1))
    # Beside an edge of the turned box, inside its unturned footprint: no overlap.
    assert not bounds.overlaps_box(box, (0.85, 0.85, -1.0), (1.2, 1.2, 1.0))


@pytest.mark.parametrize('seed', range(200))
def test_gjk_agrees_with_separating_axes_on_random_boxes(seed):
    random = np.random.default_rng(seed)
    quaternion = random.normal(size=4)
    quaternion /= np.linalg.norm(quaternion)
    w, x, y, z = quaternion
    rotation = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    box = one_box(random.uniform(-2, 2, 3), rotation, random.uniform(0.1, 1.0, 3))
    lower = random.uniform(-2, 2, 3)
    upper = lower + random.uniform(0.1, 2.0, 3)
    hull = np.array([[a, b, c] for a in (lower[0], upper[0]) for b in (lower[1], upper[1])
                     for c in (lower[2], upper[2])])
    assert bounds.overlaps_hull(box, hull) == bounds.overlaps_box(box, lower, upper)


def test_a_flat_hull_and_a_tetrahedron():
    box = one_box((0.0, 0.0, 0.0), np.eye(3), (0.5, 0.5, 0.5))
    triangle_through = [(-1.0, -1.0, 0.0), (2.0, -1.0, 0.0), (-1.0, 2.0, 0.0)]
    triangle_above = [(-1.0, -1.0, 0.6), (2.0, -1.0, 0.6), (-1.0, 2.0, 0.6)]
    assert bounds.overlaps_hull(box, triangle_through)
    assert not bounds.overlaps_hull(box, triangle_above)
    tetrahedron = [(0.4, 0.4, 0.4), (2.0, 0.4, 0.4), (0.4, 2.0, 0.4), (0.4, 0.4, 2.0)]
    assert bounds.overlaps_hull(box, tetrahedron)
    assert not bounds.overlaps_hull(box, np.array(tetrahedron) + 0.2)


def test_a_million_hull_points_are_judged_rightly():
    # How long it takes is the benchmark's core section's.
    box = one_box((0.0, 0.0, 0.0), np.eye(3), (0.5, 0.5, 0.5))
    points = np.random.default_rng(1).uniform(-4.0, 4.0, (1_000_000, 3))
    points = points[np.abs(points).max(axis=1) > 0.6]  # a cloud around the box, not in it
    assert bounds.overlaps_hull(box, points)  # their hull surrounds the box
    assert not bounds.overlaps_hull(box, points[points[:, 0] > 0.6])
