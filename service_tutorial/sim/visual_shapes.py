"""
What the world looks like, for a viewer outside MuJoCo: its visual shapes as triangle meshes.

A viewer asks visual_shapes(world) once after each spawn or delete (the world's compiled model
is then a new object) and shape_poses(world, ids) as often as it draws; both read the world's
model and data through its accessors, on the thread that steps the world. Boxes, cylinders,
capsules, spheres and ellipsoids become triangle meshes (one array for all shapes of a kind and
size, so that a viewer can draw a fleet's equal shapes as instances of one), meshes keep
MuJoCo's own vertices, and each shape keeps its colour (its material's, if it has one).
Collision shapes and planes are left out: the ground is the viewer's to draw.
"""

from collections import namedtuple
import functools

import mujoco
import numpy as np
from service_tutorial.sim.description import COLLISION_GROUP
from service_tutorial.sim.validation import SCOPE_SEPARATOR
import trimesh

# One visual geom: its id, its model ('' for the scenery), its triangles in its own frame and
# its colour.
VisualShape = namedtuple('VisualShape', 'geom_id model_name vertices faces rgba')

_GEOM = mujoco.mjtGeom
# Sides of a round shape's mesh: smooth enough at a few metres, few enough for 50 robots.
_SECTIONS = 24


@functools.lru_cache(maxsize=256)
def _primitive(kind, size):
    """Return (vertices, faces) of a MuJoCo primitive of the given size (MuJoCo's half sizes)."""
    if kind == _GEOM.mjGEOM_BOX:
        mesh = trimesh.creation.box(extents=[2.0 * half for half in size])
    elif kind == _GEOM.mjGEOM_CYLINDER:
        mesh = trimesh.creation.cylinder(radius=size[0], height=2.0 * size[1],
                                         sections=_SECTIONS)
    elif kind == _GEOM.mjGEOM_CAPSULE:
        mesh = trimesh.creation.capsule(radius=size[0], height=2.0 * size[1],
                                        count=[_SECTIONS, _SECTIONS])
    elif kind == _GEOM.mjGEOM_SPHERE:
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    else:  # an ellipsoid: a unit sphere stretched along its three axes
        mesh = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        mesh.apply_scale(size)
    vertices = np.array(mesh.vertices, dtype=np.float32)
    faces = np.array(mesh.faces, dtype=np.uint32)
    vertices.setflags(write=False)  # shared by every shape of this kind and size
    faces.setflags(write=False)
    return vertices, faces


def _shape_mesh(mj_model, geom_id):
    """Return (vertices, faces) of a geom, or None for a kind a viewer does not draw."""
    kind = int(mj_model.geom_type[geom_id])
    if kind == _GEOM.mjGEOM_MESH:
        mesh_id = int(mj_model.geom_dataid[geom_id])
        vert_start, face_start = mj_model.mesh_vertadr[mesh_id], mj_model.mesh_faceadr[mesh_id]
        vertices = mj_model.mesh_vert[vert_start:vert_start + mj_model.mesh_vertnum[mesh_id]]
        faces = mj_model.mesh_face[face_start:face_start + mj_model.mesh_facenum[mesh_id]]
        return np.array(vertices, dtype=np.float32), np.array(faces, dtype=np.uint32)
    if kind in (_GEOM.mjGEOM_BOX, _GEOM.mjGEOM_CYLINDER, _GEOM.mjGEOM_CAPSULE,
                _GEOM.mjGEOM_SPHERE, _GEOM.mjGEOM_ELLIPSOID):
        return _primitive(kind, tuple(round(float(half), 6) for half in
                                      mj_model.geom_size[geom_id]))
    return None  # planes, height fields, SDFs


def _colour(mj_model, geom_id):
    """Return a geom's rgba as MuJoCo draws it: its material's when it has one."""
    material = int(mj_model.geom_matid[geom_id])
    rgba = mj_model.mat_rgba[material] if material >= 0 else mj_model.geom_rgba[geom_id]
    return tuple(float(channel) for channel in rgba)


def model_of_body(body_name):
    """Return the name of the spawned model a body belongs to, or '' (world, scenery)."""
    model_name, separator, _ = body_name.partition(SCOPE_SEPARATOR)
    return model_name if separator else ''


def visual_shapes(world):
    """Return a VisualShape for each geom of the world with something to see, in id order."""
    mj_model = world.model
    shapes = []
    for geom_id in range(mj_model.ngeom):
        if int(mj_model.geom_group[geom_id]) == COLLISION_GROUP:
            continue
        mesh, rgba = _shape_mesh(mj_model, geom_id), _colour(mj_model, geom_id)
        if mesh is None or rgba[3] == 0.0:
            continue
        body_name = mj_model.body(int(mj_model.geom_bodyid[geom_id])).name
        shapes.append(VisualShape(geom_id, model_of_body(body_name), mesh[0], mesh[1], rgba))
    return shapes


def shape_poses(world, geom_ids):
    """Return the geoms' world positions (n x 3) and orientations (n x 4, wxyz), as copies."""
    mj_model = world.model
    if mj_model.nbody > 1:
        world.body_state(1)  # brings the kinematics up to date after a move or a step
    data = world.data
    body = data.xquat[mj_model.geom_bodyid[geom_ids]]
    local = mj_model.geom_quat[geom_ids]
    return data.geom_xpos[geom_ids].copy(), _multiply(body, local)


def _multiply(first, second):
    """Return the Hamilton products of two arrays of wxyz quaternions, row by row."""
    w1, x1, y1, z1 = first.T
    w2, x2, y2, z2 = second.T
    return np.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2,
                     w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                     w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=1)
