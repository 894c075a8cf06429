"""
What an SDF link holds: its inertial, its collisions and visuals, read with SDF's defaults.

A link without <inertial> has a mass of 1 kg and an identity inertia about its origin, as
sdformat gives it; a shape's size has SDF's default where it is not written (a box 1 m a side,
a sphere of radius 1 m...). A mesh is found by the uri rules of paths.py: one that is refused
refuses the model (AssetError), one that is not there, or of a format the world does not read,
is left out and named. A plane is infinite, as gz-sim collides with it: scenery only. A
<sensor> is read as a URDF's <gazebo reference> sensor is (urdf/gazebo.py), posed in the link's
frame: gz-sim's own (no <plugin>) or Gazebo Classic's plugins in it; one of a type the world
does not simulate is named.
"""

from dataclasses import dataclass
import os

import numpy as np

from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import kind_of
from service_tutorial.sim.sdf.elements import boolean, child_text, first_child, MAX_INERTIA
from service_tutorial.sim.sdf.elements import MAX_MASS
from service_tutorial.sim.sdf.elements import MAX_SCALE, name_of, number, numbers
from service_tutorial.sim.sdf.paths import UriMissing, UriRefused
from service_tutorial.sim.sdf.poses import compose, IDENTITY, read_pose, relative
from service_tutorial.sim.urdf.builder import check_size
from service_tutorial.sim.urdf.gazebo import gazebo_colour, sensor_block
from service_tutorial.sim.urdf.gazebo import sensor_plugin_blocks
from service_tutorial.sim.urdf.meshes import MESH_FORMATS
from service_tutorial.sim.validation import AssetError, DescriptionError, quoted

SHAPES = ('box', 'sphere', 'cylinder', 'capsule', 'ellipsoid', 'plane', 'mesh')
# Shapes of SDF the world does not build: left out, and named in the file's note.
OTHER_SHAPES = ('heightmap', 'polyline', 'cone', 'image')
# Per shape, its size elements with SDF's defaults, and what each number is to an extent.
_SIZES = {
    'box': (('size', (1.0, 1.0, 1.0)),),
    'sphere': (('radius', (1.0,)),),
    'cylinder': (('radius', (1.0,)), ('length', (1.0,))),
    'capsule': (('radius', (0.5,)), ('length', (1.0,))),
    'ellipsoid': (('radii', (1.0, 1.0, 1.0)),),
    'plane': (('size', (1.0, 1.0)),),
}
_ACROSS = {'box': (1.0, 1.0, 1.0), 'sphere': (2.0,), 'cylinder': (2.0, 1.0),
           'capsule': (2.0, 1.0), 'ellipsoid': (2.0, 2.0, 2.0), 'plane': (1.0, 1.0)}


@dataclass(frozen=True)
class Shape:
    """A collision or visual of a link: its shape, size and pose in the link's frame."""

    name: str
    kind: str  # one of SHAPES
    pose: tuple  # (position, quaternion) in the link's frame
    size: tuple = ()  # SDF's numbers: box x y z; sphere r; cylinder and capsule r, length
    uri: str = ''  # a mesh's uri as written
    path: str = ''  # a mesh's real path; '' if it is left out
    missing: str = ''  # why a mesh is left out
    scale: tuple = (1.0, 1.0, 1.0)
    rgba: tuple = None  # a visual's colour
    friction: float = None  # a collision's ODE mu (the smaller of mu and mu2)
    normal: tuple = (0.0, 0.0, 1.0)  # a plane's


@dataclass(frozen=True)
class Link:
    """A link: its pose in the model frame, its mass properties and its shapes."""

    name: str  # scoped in the model: nested::link
    pose: tuple  # (position, quaternion) in the model frame
    mass: float
    inertial_pose: tuple  # the centre of mass and inertia axes, in the link's frame
    inertia: np.ndarray  # 3x3, about the centre of mass in the inertial frame
    collisions: tuple
    visuals: tuple
    gravity: bool = True
    self_collide: bool = False
    sensors: tuple = ()  # urdf.gazebo.PluginBlocks of its <sensor>s, each with its sensor


class LinkReader:
    """Reads the links of one model scope, their poses resolved in its frame graph."""

    def __init__(self, reading, graph, version, base_dir, static):
        """Read for a SdfReading, in a FrameGraph, of a file's version and folder."""
        self.reading = reading
        self.graph = graph
        self.version = version
        self.base_dir = base_dir
        self.static = static

    def link(self, element, self_collide):
        """Return the Link of a <link>."""
        name = element.get('name')
        what = f'link {quoted(name)} of {self.graph.what}'
        self.reading.notes.children(element, 'link', what)
        if boolean(element, 'kinematic', False, what):
            self.reading.notes.add('<kinematic>', what)
        pose = self.graph.pose(name, f'link {quoted(name)}')
        mass, inertial_pose, inertia = self._inertial(first_child(element, 'inertial'), pose, what)
        shapes = {'collision': [], 'visual': []}
        for kind in shapes:
            names = set()
            for child in element.iterchildren(kind):
                shape_name = name_of(child, what)
                if shape_name in names:
                    raise DescriptionError(f'{what} has two {kind}s named {quoted(shape_name)}')
                names.add(shape_name)
                shape = self._shape(child, kind, shape_name, pose, what)
                if shape is not None:
                    shapes[kind].append(shape)
        return Link(name=name, pose=pose, mass=mass, inertial_pose=inertial_pose,
                    inertia=inertia, collisions=tuple(shapes['collision']),
                    visuals=tuple(shapes['visual']),
                    gravity=boolean(element, 'gravity', True, what),
                    self_collide=boolean(element, 'self_collide', self_collide, what),
                    sensors=self._sensors(element, name, pose, what))

    def _sensors(self, element, link_name, link_pose, what):
        """Return the PluginBlocks of a link's <sensor>s, naming those not simulated."""
        blocks = []
        for child in element.iterchildren('sensor'):
            sensor_name = name_of(child, what)
            shown = f'sensor {quoted(sensor_name)} of {what}'
            try:
                sensor = sensor_block(child, link_name, self._in_link(first_child(child, 'pose'),
                                                                      link_pose, shown))
            except UrdfError as error:
                raise DescriptionError(str(error)) from None
            found = sensor_plugin_blocks(child, sensor)
            if found is None:
                self.reading.notes.add(f'<sensor type={quoted(sensor.sensor_type)}>', shown)
            for block in found or ():
                if kind_of(block.filename) is None:
                    self.reading.ignore_plugin(block.filename, shown)
                else:
                    blocks.append(block)
        return tuple(blocks)

    def _in_link(self, element, link_pose, asker):
        """Return the pose of a link's element in the link's frame."""
        pose, relative_to = read_pose(element, self.version, asker)
        if not relative_to:
            return pose
        return relative(link_pose, compose(self.graph.pose(relative_to, asker), pose))

    def _inertial(self, element, link_pose, what):
        """Return (mass, inertial pose, inertia tensor) of an <inertial>, SDF's if none."""
        if element is None:
            return 1.0, IDENTITY, np.eye(3)
        shown = f'<inertial> of {what}'
        self.reading.notes.children(element, 'inertial', shown)
        if element.get('auto', '').strip().lower() in ('true', '1'):
            self.reading.notes.add('<inertial auto="true"> (its values are used)', what)
        mass = number(element, 'mass', 1.0, shown, maximum=MAX_MASS)
        if mass <= 0.0 and not self.static:
            raise DescriptionError(f'{shown} <mass> must be positive: {mass:g}')
        inertia = first_child(element, 'inertia')
        values = {}
        for key, default in (('ixx', 1.0), ('iyy', 1.0), ('izz', 1.0), ('ixy', 0.0),
                             ('ixz', 0.0), ('iyz', 0.0)):
            values[key] = default if inertia is None else number(
                inertia, key, default, f'{shown} <inertia>', minimum=-MAX_INERTIA,
                maximum=MAX_INERTIA)
        tensor = np.array([[values['ixx'], values['ixy'], values['ixz']],
                           [values['ixy'], values['iyy'], values['iyz']],
                           [values['ixz'], values['iyz'], values['izz']]])
        return mass, self._in_link(first_child(element, 'pose'), link_pose, shown), tensor

    def _shape(self, element, kind, name, link_pose, what):
        """Return the Shape of a <collision> or <visual>, or None if it has none to build."""
        shown = f'{kind} {quoted(name)} of {what}'
        self.reading.notes.children(element, kind, shown)
        geometry = first_child(element, 'geometry')
        if geometry is None:
            raise DescriptionError(f'{shown} has no <geometry>')
        self.reading.notes.children(geometry, 'geometry', shown)
        found = [child for child in geometry if isinstance(child.tag, str)]
        if len(found) != 1:
            raise DescriptionError(f'{shown} must have one shape in its <geometry>, not '
                                   f'{len(found)}')
        shape = found[0]
        if shape.tag not in SHAPES:
            return None  # <empty/>, or noted above as not simulated
        pose = self._in_link(first_child(element, 'pose'), link_pose, shown)
        fields = {'name': name, 'kind': shape.tag, 'pose': pose}
        if shape.tag == 'mesh':
            fields.update(self._mesh(shape, shown))
        else:
            fields['size'] = self._size(shape, shown)
        if shape.tag == 'plane':
            normal = np.array(numbers(child_text(shape, 'normal') or '0 0 1', 3,
                                      f'{shown} plane <normal>'))
            if not np.linalg.norm(normal) > 1e-9:
                raise DescriptionError(f'{shown} plane <normal> is zero')
            fields['normal'] = tuple(normal / np.linalg.norm(normal))
        if kind == 'visual':
            fields['rgba'] = self._colour(element, shown)
        else:
            fields['friction'] = self._friction(element, shown)
        return Shape(**fields)

    def _size(self, shape, shown):
        size = []
        for tag, default in _SIZES[shape.tag]:
            text = child_text(shape, tag)
            size.extend(default if text is None else numbers(
                text, len(default), f'{shown} {shape.tag} <{tag}>'))
        try:
            check_size(np.array(size), len(size), f'{shown} {shape.tag} size',
                       across=_ACROSS[shape.tag])
        except UrdfError as error:
            raise DescriptionError(str(error)) from None
        return tuple(size)

    def _mesh(self, shape, shown):
        """Return the fields of a mesh: its uri, real path or why it is left out, scale."""
        self.reading.notes.children(shape, 'mesh', shown)
        if first_child(shape, 'submesh') is not None:
            self.reading.notes.add('<submesh> (the whole mesh is used)', shown)
        uri = child_text(shape, 'uri') or ''
        if not uri:
            raise DescriptionError(f'{shown} mesh has no <uri>')
        scale = tuple(numbers(child_text(shape, 'scale') or '1 1 1', 3,
                              f'{shown} mesh <scale>', limit=MAX_SCALE))
        if not all(scale):
            raise DescriptionError(f'{shown} mesh <scale> has a zero: {list(scale)}')
        fields = {'uri': uri, 'scale': scale}
        try:
            path = self.reading.paths.locate(uri, self.base_dir, f'mesh of {shown}')
        except UriRefused as refused:
            raise AssetError(str(refused)) from None
        except UriMissing as missing:
            return {**fields, 'missing': missing.reason}
        if not os.path.isfile(path):
            return {**fields, 'missing': 'it is a folder'}
        if os.path.splitext(path)[1].lower() not in MESH_FORMATS:
            return {**fields, 'missing': f'its format is none of {", ".join(MESH_FORMATS)}'}
        return {**fields, 'path': path}

    def _colour(self, element, shown):
        """Return a visual's RGBA: its diffuse or ambient, a Gazebo material script's, or None."""
        material = first_child(element, 'material')
        if material is None:
            return None
        rgba = None
        script = first_child(material, 'script')
        if script is not None and child_text(script, 'name'):
            rgba = gazebo_colour(child_text(script, 'name'))
        for tag in ('ambient', 'diffuse'):
            text = child_text(material, tag)
            if text:
                values = numbers(text, len(text.split()) if len(text.split()) in (3, 4) else 4,
                                 f'{shown} <material><{tag}>')
                rgba = tuple(min(max(value, 0.0), 1.0)
                             for value in values + [1.0] * (4 - len(values)))
        transparency = number(element, 'transparency', 0.0, shown, minimum=0.0, maximum=1.0)
        if rgba is not None and transparency:
            rgba = rgba[:3] + (rgba[3] * (1.0 - transparency),)
        return rgba

    def _friction(self, element, shown):
        """Return a collision's friction, ODE's mu and mu2 (the smaller), or None."""
        surface = first_child(element, 'surface')
        if surface is None:
            return None
        friction = first_child(surface, 'friction')
        ode = first_child(friction, 'ode') if friction is not None else None
        if ode is None:
            return None
        values = [number(ode, tag, None, f'{shown} <surface><friction><ode>', maximum=1e9)
                  for tag in ('mu', 'mu2')]
        values = [value for value in values if value is not None and value >= 0.0]
        return min(values) if values else None
