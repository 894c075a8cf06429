"""
The <origin> of a URDF's joints, inertials, visuals and collisions, read once as poses.

yourdfpy would turn each into a 4x4 matrix through trimesh, only for the builder to turn it
back into a position and a quaternion: more than half of yourdfpy's parse of a robot with
dozens of origins (R2-D2 has 41). So they are read here and taken out of the tree it gets.
"""

import numpy as np
from service_tutorial.sim import frames
from service_tutorial.sim.description import parse_numbers


def take_origins(root):
    """
    Take the <origin> of every joint, inertial, visual and collision out of root.

    Return each as (position, quaternion), keyed by where it stood: ('joint', name),
    ('inertial', link), ('visual', link, index) or ('collision', link, index), as yourdfpy
    lists them. check_structure() has checked their numbers already. As in yourdfpy, an
    element's first <origin> counts. (iterchildren(), not lxml's find(): half the time.)
    """
    origins = {}

    def take(element, key):
        found = list(element.iterchildren('origin'))
        if found:
            origins[key] = _origin_pose(found[0], key)
            for origin in found:
                element.remove(origin)

    for joint in root.iterchildren('joint'):
        take(joint, ('joint', joint.get('name')))
    for link in root.iterchildren('link'):
        name = link.get('name')
        inertial = next(link.iterchildren('inertial'), None)
        if inertial is not None:
            take(inertial, ('inertial', name))
        for kind in ('visual', 'collision'):
            for index, element in enumerate(link.iterchildren(kind)):
                take(element, (kind, name, index))
    return origins


def _origin_pose(origin, key):
    """Return (position, quaternion) of an <origin>: URDF's rpy turns about fixed x, y, z."""
    where = f"{key[0]} '{key[1]}' <origin"
    xyz, rpy = origin.get('xyz'), origin.get('rpy')
    position = np.array(parse_numbers(xyz, f'{where} xyz>') if xyz else (0.0, 0.0, 0.0))
    angles = parse_numbers(rpy, f'{where} rpy>') if rpy else None
    if angles and any(angles):
        return position, frames.rpy_quaternion(angles)
    return position, np.array(frames.IDENTITY_QUATERNION)
