"""
What the world looks like, for a viewer outside MuJoCo: each body's visual shapes as meshes.

A viewer asks visual_bodies(world) once after each spawn or delete (the world's compiled model
is then a new object) and body_poses(world, ids) as often as it draws; both read the world's
model and data through its accessors, on the thread that steps the world. Boxes, cylinders,
capsules, spheres and ellipsoids become triangle meshes, meshes keep MuJoCo's own vertices, and
each shape keeps its colour (its material's, if it has one) and its pose in its body. Collision
shapes and planes are left out: the ground is the viewer's to draw.
"""

from collections import namedtuple
import functools

import mujoco
import numpy as np
from service_tutorial.sim.description import COLLISION_GROUP
from service_tutorial.sim.validation import SCOPE_SEPARATOR
import trimesh

# One shape of a body: its triangles in its own frame, its colour, its pose in the body.
VisualShape = namedtuple('VisualShape', 'vertices faces rgba position wxyz')
# A body with at least one visual shape; model_name is '' for the scenery's bodies.
VisualBody = namedtuple('VisualBody', 'body_id name model_name shapes')

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
    return (np.asarray(mesh.vertices, dtype=np.float32),
            np.asarray(mesh.faces, dtype=np.uint32))


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


def visual_bodies(world):
    """Return a VisualBody for each body of the world with something to see, in id order."""
    mj_model = world.model
    shapes = {}
    for geom_id in range(mj_model.ngeom):
        if int(mj_model.geom_group[geom_id]) == COLLISION_GROUP:
            continue
        mesh = _shape_mesh(mj_model, geom_id)
        if mesh is None or _colour(mj_model, geom_id)[3] == 0.0:
            continue
        shapes.setdefault(int(mj_model.geom_bodyid[geom_id]), []).append(VisualShape(
            mesh[0], mesh[1], _colour(mj_model, geom_id),
            tuple(float(x) for x in mj_model.geom_pos[geom_id]),
            tuple(float(x) for x in mj_model.geom_quat[geom_id])))
    bodies = []
    for body_id in sorted(shapes):
        name = mj_model.body(body_id).name
        bodies.append(VisualBody(body_id, name, model_of_body(name), tuple(shapes[body_id])))
    return bodies


def body_poses(world, body_ids):
    """Return copies of the bodies' world positions (n x 3) and orientations (n x 4, wxyz)."""
    moving = [body_id for body_id in body_ids if body_id != 0]
    if moving:
        world.body_state(moving[0])  # brings the kinematics up to date after a move or a step
    data = world.data
    return data.xpos[body_ids].copy(), data.xquat[body_ids].copy()
