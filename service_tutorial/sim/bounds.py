"""
Where a model's collision geometry is, and whether it overlaps a sphere, a box or a hull.

Every collision geom of a model is taken as the oriented box MuJoCo keeps around it
(geom_aabb, in the geom's frame, placed by geom_xpos and geom_xmat): exact for boxes, snug for
spheres, cylinders and capsules along their axes, and the mesh's own box for meshes. A sphere
overlaps a box when the box's closest point to the centre is within the radius; an
axis-aligned box by separating axes; a convex hull by GJK on the hull's points and the box's
corners. No ROS.
"""

from dataclasses import dataclass

import mujoco
import numpy as np
from service_tutorial.sim.description import COLLISION_GROUP

# Corners of the unit box, as signs of its half sizes: (8, 3).
_CORNER_SIGNS = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)],
                         dtype=float)
# Touching counts as overlapping, up to this much (m).
TOLERANCE = 1e-9
# GJK reaches an answer in a few iterations; this bounds a degenerate case.
_GJK_ITERATIONS = 64


@dataclass(frozen=True, eq=False)
class OrientedBoxes:
    """Boxes in the world frame: centres (n, 3), rotations (n, 3, 3), half sizes (n, 3)."""

    centres: np.ndarray
    rotations: np.ndarray  # columns: a box's axes in the world frame
    half_sizes: np.ndarray

    def __len__(self):
        """Return the number of boxes."""
        return len(self.centres)

    def corners(self):
        """Return the corners of every box in the world frame: (n, 8, 3)."""
        local = _CORNER_SIGNS[None, :, :] * self.half_sizes[:, None, :]
        return self.centres[:, None, :] + np.einsum('nij,nkj->nki', self.rotations, local)


def collision_boxes(world, model):
    """Return the OrientedBoxes around the collision geoms of a world's model."""
    world.body_state(model.root_id)  # brings the world's kinematics up to date
    return geom_boxes(world.model, world.data, _collision_geoms(world.model, model.root_id))


def _collision_geoms(mj_model, root_id):
    """Return the ids of the collision geoms of the tree under a root body."""
    # A URDF's collision geoms are in COLLISION_GROUP; an MJCF's are any that collide.
    collides = (mj_model.geom_contype | mj_model.geom_conaffinity) != 0
    return np.flatnonzero(((mj_model.geom_group == COLLISION_GROUP) | collides)
                          & (mj_model.body_rootid[mj_model.geom_bodyid] == root_id))


def geom_boxes(mj_model, data, geoms):
    """Return the OrientedBoxes around some geoms of a compiled model whose kinematics are done."""
    rotations = data.geom_xmat[geoms].reshape(-1, 3, 3)
    aabb = mj_model.geom_aabb[geoms]
    centres = data.geom_xpos[geoms] + np.einsum('nij,nj->ni', rotations, aabb[:, :3])
    return OrientedBoxes(centres=centres, rotations=rotations, half_sizes=aabb[:, 3:].copy())


def box_in_base_frame(world, model):
    """
    Return (lower, upper) corners of the box around a model's collision geometry, or None.

    The corners are in the frame of the model's base (root) link; None: it has no collision
    geometry.
    """
    return box_in_body_frame(collision_boxes(world, model), world.data, model.root_id)


def box_in_body_frame(boxes, data, body_id):
    """Return (lower, upper) corners of the box around boxes in a body's frame, or None."""
    if not len(boxes):
        return None
    rotation = data.xmat[body_id].reshape(3, 3)
    local = (boxes.corners().reshape(-1, 3) - data.xpos[body_id]) @ rotation
    return local.min(axis=0), local.max(axis=0)


def description_box(description):
    """
    Return the box around a RobotDescription's collision geometry in its root link's frame.

    The robot's spec is compiled alone, away from any world, so the box is the one
    box_in_base_frame() gives once it is spawned. (lower, upper), or None without collision
    geometry.
    """
    mj_model = description.spec.compile()
    data = mujoco.MjData(mj_model)
    mujoco.mj_kinematics(mj_model, data)
    root = mj_model.body(description.root_link).id
    return box_in_body_frame(geom_boxes(mj_model, data, _collision_geoms(mj_model, root)),
                             data, root)


def overlaps_sphere(boxes, centre, radius):
    """Return True if any box comes within radius of centre."""
    if not len(boxes):
        return False
    local = np.einsum('nji,nj->ni', boxes.rotations, np.asarray(centre) - boxes.centres)
    nearest = np.clip(local, -boxes.half_sizes, boxes.half_sizes)
    distance = np.linalg.norm(local - nearest, axis=1)
    return bool(np.any(distance <= radius + TOLERANCE))


def overlaps_box(boxes, lower, upper):
    """Return True if any box overlaps the axis-aligned box between corners lower and upper."""
    if not len(boxes):
        return False
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    centre, half = (lower + upper) / 2.0, (upper - lower) / 2.0
    offsets = boxes.centres - centre
    for index in range(len(boxes)):
        if not _separated(offsets[index], half, boxes.rotations[index],
                          boxes.half_sizes[index]):
            return True
    return False


def _separated(offset, half, rotation, box_half):
    """Separating axes of an axis-aligned box and an oriented one, offset from its centre."""
    axes = [np.eye(3), rotation.T]
    axes.append(np.array([np.cross(world_axis, box_axis) for world_axis in np.eye(3)
                          for box_axis in rotation.T]))
    candidates = np.concatenate(axes)
    lengths = np.linalg.norm(candidates, axis=1)
    candidates = candidates[lengths > 1e-12] / lengths[lengths > 1e-12, None]
    reach = (np.abs(candidates) @ half
             + np.abs(candidates @ rotation) @ box_half)
    return bool(np.any(np.abs(candidates @ offset) > reach + TOLERANCE))


def overlaps_hull(boxes, points):
    """Return True if any box overlaps the convex hull of points (m, 3)."""
    points = np.asarray(points, float)
    return any(convex_overlap(corners, points) for corners in boxes.corners())


def convex_overlap(first, second):
    """Return True if the convex hulls of two point sets (n, 3) and (m, 3) share a point (GJK)."""
    def support(direction):
        return first[np.argmax(first @ direction)] - second[np.argmin(second @ direction)]

    direction = first.mean(axis=0) - second.mean(axis=0)
    if not np.any(direction):
        direction = np.array([1.0, 0.0, 0.0])
    simplex = [support(direction)]
    direction = -simplex[0]
    for _ in range(_GJK_ITERATIONS):
        if np.dot(direction, direction) <= TOLERANCE * TOLERANCE:
            return True  # the origin lies on the simplex
        point = support(direction)
        if np.dot(point, direction) < -TOLERANCE * np.linalg.norm(direction):
            return False  # nothing of the difference lies beyond the origin
        simplex.append(point)
        simplex, direction, enclosed = _closer_simplex(simplex, direction)
        if enclosed:
            return True
    return True


def _closer_simplex(simplex, direction):
    """
    Reduce the simplex to its feature nearest the origin.

    Return that feature, the direction to search next, and whether the simplex encloses the
    origin.
    """
    if len(simplex) == 2:
        return _line(simplex)
    if len(simplex) == 3:
        return _triangle(simplex)
    return _tetrahedron(simplex)


def _line(simplex):
    b, a = simplex
    ab, ao = b - a, -a
    if np.dot(ab, ao) > 0:
        direction = np.cross(np.cross(ab, ao), ab)
        if not np.any(direction):  # the origin lies on the line
            return [b, a], direction, True
        return [b, a], direction, False
    return [a], ao, False


def _triangle(simplex):
    c, b, a = simplex
    ab, ac, ao = b - a, c - a, -a
    normal = np.cross(ab, ac)
    if np.dot(np.cross(normal, ac), ao) > 0:
        if np.dot(ac, ao) > 0:
            return [c, a], np.cross(np.cross(ac, ao), ac), False
        return _line([b, a])
    if np.dot(np.cross(ab, normal), ao) > 0:
        return _line([b, a])
    side = np.dot(normal, ao)
    if side > 0:
        return [c, b, a], normal, False
    if side < 0:
        return [b, c, a], -normal, False
    return [c, b, a], normal, True  # the origin lies in the triangle's plane, inside it


def _tetrahedron(simplex):
    d, c, b, a = simplex
    ao = -a
    for first, second, opposite in ((b, c, d), (c, d, b), (d, b, c)):
        normal = np.cross(first - a, second - a)
        if np.dot(normal, opposite - a) > 0:
            normal = -normal
        if np.dot(normal, ao) > TOLERANCE * np.linalg.norm(normal):
            return _triangle([second, first, a])
    return simplex, np.zeros(3), True
