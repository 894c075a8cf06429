"""
World files: a world's scenery, its start-up models and its named poses, in one small file.

    <world name="parking">
      <description>A wall with a crate before it, to park tinybot in front of.</description>
      <tag>lesson</tag>
      <scenery uri="package://service_tutorial/worlds/parking.xml"/>
      <named_pose name="parking_spot">
        <description>In front of the crate, facing it</description>
        <tag>parking</tag>
        <origin xyz="2.2 0 0" rpy="0 0 0"/>
        <bounds type="box" min="1.9 -0.3 0" max="2.5 0.3 0.4"/>
      </named_pose>
      <model name="tinybot" uri="package://service_tutorial/models/tinybot.urdf"
             pose="tinybot_start"/>
    </world>

A file names its scenery and models by package:// or file:// uri inside an installed package's
share (package_files.py), or by a name in the world file's own folder; a world given as text
only by uri. No scenery is the bare plane. A model stands at a named pose of the world or at an
<origin> of its own (the origin of the world if neither). Poses are in the world frame, rpy as
in URDF; bounds are a box (two opposite corners) or a sphere (centre and radius) in the world
frame, where something may stand at the pose. Elements the world does not know are listed in
WorldFile.unsupported, for the loader to refuse or to ignore.

A Gazebo world, SDF (<sdf><world>, a .world or .sdf file, or an installed .sdf.xacro expanded with
its default arguments), is a world file too (sdf/world.py): its static models are its scenery, its
other models its start-up models, each from its own SDF; its <physics> and <gravity> are the
world's; what it holds and the world does not simulate is listed in WorldFile.unsupported, and the
models left out in WorldFile.left_out.
"""

from dataclasses import dataclass, field
import os

import mujoco
import numpy as np
from service_tutorial.sim.description import parse_numbers, UrdfError
from service_tutorial.sim.package_files import confined_path, PackageFileError, within
from service_tutorial.sim.robot_files import expand_xacro, read_description_text, RobotSource
from service_tutorial.sim.sdf.reader import parse_sdf
from service_tutorial.sim.sdf.world import read_sdf_world, TAG as SDF_TAG, world_name
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES, parse_xml
from service_tutorial.sim.validation import check_model_name, quoted, Reason, WorldError

# A world file is small: a few poses and models, never megabytes.
MAX_WORLD_FILE_BYTES = 1 << 20
MAX_ENTRIES = 1000  # named poses, models or tags of one world
MAX_TEXT_LENGTH = 10000  # a description
MAX_NAME_LENGTH = 256  # a world's, a pose's or a tag's
MAX_COORDINATE = 1e6  # metres
WORLD_FILE_SUFFIX = '.world.xml'
# Gazebo's worlds, SDF, are found in a worlds/ folder by these too; xacro is expanded.
SDF_XACRO_SUFFIX = '.sdf.xacro'
SDF_WORLD_SUFFIXES = ('.world', '.sdf', SDF_XACRO_SUFFIX)
WORLD_SUFFIXES = (WORLD_FILE_SUFFIX,) + SDF_WORLD_SUFFIXES
# Scenery files load as worlds of their own; other simulators' formats are named.
SCENERY_ROOTS = ('robot', 'mujoco')
OTHER_FORMATS = {'gazebo': "Gazebo Classic's <gazebo> (write it as SDF, <sdf>)"}


class WorldFileError(WorldError):
    """A world file the world cannot load; its reason says why (NOT_PARSEABLE if none)."""

    reason = Reason.NOT_PARSEABLE


@dataclass(frozen=True)
class NamedPose:
    """A pose the world names: where to spawn, park or go."""

    name: str
    description: str
    tags: tuple
    position: tuple
    orientation: tuple  # (w, x, y, z)
    bounds_type: str  # 'box', 'sphere' or '' for none
    bounds_points: tuple  # box: two corners; sphere: centre, (radius, 0, 0)


@dataclass(frozen=True)
class StartModel:
    """A model the world spawns when it loads: its file (or its text), name, namespace, pose."""

    name: str  # '' for the name inside the file
    path: str  # '' for a model whose text the world file holds (source)
    namespace: str
    position: tuple
    orientation: tuple  # (w, x, y, z)
    source: object = None  # a robot_files.RobotSource: an SDF world's model


@dataclass(frozen=True)
class WorldFile:
    """What one world file says."""

    name: str
    description: str
    tags: tuple
    scenery: str  # the scenery file's real path, '' for the bare plane
    models: tuple
    named_poses: dict = field(default_factory=dict)  # name -> NamedPose, in file order
    unsupported: tuple = ()  # elements the world does not know, as '<tag>'
    scenery_text: str = ''  # a scenery given as text, in place of a file
    physics: tuple = None  # (timestep, gravity) the world says, None for the node's own
    sdf_world: object = None  # an SDF world read (sdf/world.py): its static models
    left_out: tuple = ()  # names of models left out: none of their collisions is there
    spherical_coordinates: object = None  # where its origin lies on the Earth (SDF), or None


def read_world_file(path, package_share, *, shown=None, scenery_alone=False, listing=False):
    """
    Return the WorldFile of a file (checked against the roots by its caller).

    scenery_alone: a URDF or MJCF file is a world of that scenery and nothing else; listing:
    an SDF world's name is all that is read, for a list of worlds.
    """
    shown = quoted(shown or path)
    limit = MAX_MODEL_XML_BYTES if scenery_alone or path.endswith(SDF_WORLD_SUFFIXES) \
        else MAX_WORLD_FILE_BYTES
    if path.endswith(SDF_XACRO_SUFFIX):  # with its default arguments, as a launch file would
        try:
            data = expand_xacro(path).encode('utf-8')
        except WorldError as error:
            raise WorldFileError(str(error), error.reason) from None
    else:
        try:
            with open(path, 'rb') as world_file:
                data = world_file.read(limit + 1)
        except OSError as error:
            raise WorldFileError(f'world file {shown} cannot be read: {error.strerror}',
                                 Reason.NO_RESOURCE) from None
    name = os.path.basename(path)
    default_name = next((name[:-len(suffix)] for suffix in (WORLD_FILE_SUFFIX, SDF_XACRO_SUFFIX)
                         if name.endswith(suffix)), os.path.splitext(name)[0])
    return parse_world(data, f'world file {shown}', os.path.dirname(path), package_share,
                       default_name=default_name, scenery_path=path if scenery_alone else None,
                       listing=listing)


def parse_world(data, what, base_dir, package_share, *, default_name='world',
                scenery_path=None, scenery_alone=False, listing=False):
    """
    Return the WorldFile of a world's XML (bytes); base_dir None: it names files by uri.

    scenery_path (a file's) or scenery_alone (a text's): URDF or MJCF is a world of that
    scenery alone, read by the world's reader of robot files when the world is loaded.
    """
    if isinstance(data, str):
        data = data.encode('utf-8')
    alone = scenery_alone or scenery_path is not None
    limit = MAX_MODEL_XML_BYTES if alone or data.lstrip()[:200].find(b'<sdf') >= 0 \
        else MAX_WORLD_FILE_BYTES
    if len(data) > limit:
        raise WorldFileError(f'{what} is larger than {limit} bytes')
    try:
        root = parse_xml(data, what)
    except UrdfError as error:
        raise WorldFileError(str(error)) from None
    tag = root.tag if isinstance(root.tag, str) else ''
    if alone and tag in SCENERY_ROOTS:
        return WorldFile(name=default_name if scenery_path else 'scenery',
                         description=f'the scenery {what} alone' if scenery_path
                         else 'a scenery given as text', tags=(),
                         scenery=scenery_path or '', models=(),
                         scenery_text='' if scenery_path else data.decode('utf-8'))
    if tag == 'sdf':
        return _sdf_world(data, what, base_dir, package_share, listing)
    if tag in OTHER_FORMATS:
        raise WorldFileError(f'{what} is {OTHER_FORMATS[tag]} (root element <{tag}>); this '
                             'world loads world files (<world>), SDF, URDF and MJCF',
                             Reason.UNSUPPORTED_FORMAT)
    if len(data) > MAX_WORLD_FILE_BYTES:
        raise WorldFileError(f'{what} is larger than {MAX_WORLD_FILE_BYTES} bytes')
    reader = _Reader(what, base_dir, package_share)
    try:
        return reader.world(root, default_name)
    except UrdfError as error:  # parse_numbers' refusals
        raise WorldFileError(f'{what}: {error}') from None


def _sdf_world(data, what, base_dir, package_share, listing):
    """Return the WorldFile of an SDF world; listing: its name alone is read."""
    try:
        if listing:
            root, version = parse_sdf(data, what)
            return WorldFile(name=world_name(root, what), description=_sdf_description(version),
                             tags=(SDF_TAG,), scenery='', models=())
        world = read_sdf_world(data, what, base_dir, package_share, read_description_text)
    except WorldError as error:
        raise WorldFileError(str(error), error.reason) from None
    models = tuple(StartModel(name=entity.name, path='', namespace='', position=entity.position,
                              orientation=entity.orientation,
                              source=RobotSource(entity.text, 'sdf', entity.name,
                                                 entity.base_dir))
                   for entity in world.entities)
    return WorldFile(name=world.name, description=_sdf_description(world.version),
                     tags=(SDF_TAG,),
                     scenery='', models=models, unsupported=world.not_simulated,
                     physics=(world.timestep, world.gravity), sdf_world=world,
                     left_out=world.left_out, spherical_coordinates=world.spherical_coordinates)


def _sdf_description(version):
    return f'a Gazebo world (SDF {version[0]}.{version[1]})'


class _Reader:
    """Reads the elements of one world file, resolving its files inside the roots."""

    def __init__(self, what, base_dir, package_share):
        self.what = what
        self.base_dir = base_dir
        self.package_share = package_share
        self.unsupported = []

    def fail(self, message, reason=Reason.NOT_PARSEABLE):
        raise WorldFileError(f'{self.what}: {message}', reason)

    def world(self, root, default_name):
        if root.tag != 'world':
            self.fail(f'the root element is <{str(root.tag)[:40]}>, not <world>',
                      Reason.UNSUPPORTED_FORMAT)
        name = self.name(root.get('name') or default_name, 'world name')
        description, tags, scenery = '', [], ''
        models, poses = [], {}
        children = [child for child in root if isinstance(child.tag, str)]
        if len(children) > 3 * MAX_ENTRIES:
            self.fail(f'has {len(children)} elements, more than {3 * MAX_ENTRIES}')
        for child in children:
            if child.tag == 'description':
                description = self.text(child)
            elif child.tag == 'tag':
                tags.append(self.name(child.text or '', 'tag'))
            elif child.tag == 'scenery':
                if scenery:
                    self.fail('has more than one <scenery>')
                scenery = self.file(child.get('uri'), '<scenery>')
            elif child.tag == 'named_pose':
                pose = self.named_pose(child)
                if pose.name in poses:
                    self.fail(f'names the pose {quoted(pose.name)} twice')
                poses[pose.name] = pose
            elif child.tag == 'model':
                models.append(child)
            else:
                self.unsupported.append(f'<{child.tag[:40]}>')
        if max(len(tags), len(poses), len(models)) > MAX_ENTRIES:
            self.fail(f'has more than {MAX_ENTRIES} tags, named poses or models')
        return WorldFile(
            name=name, description=description, tags=tuple(dict.fromkeys(tags)),
            scenery=scenery, models=tuple(self.model(element, poses) for element in models),
            named_poses=poses, unsupported=tuple(self.unsupported))

    def name(self, text, what):
        text = text.strip()
        if not text or len(text) > MAX_NAME_LENGTH or not text.isprintable():
            self.fail(f'{what} {quoted(text)} must be 1 to {MAX_NAME_LENGTH} printable '
                      'characters')
        return text

    def text(self, element):
        text = ' '.join((element.text or '').split())
        if len(text) > MAX_TEXT_LENGTH:
            self.fail(f'<{element.tag}> is longer than {MAX_TEXT_LENGTH} characters')
        return text

    def file(self, uri, what):
        """Return the real path of a file the world names, inside the roots."""
        if not uri:
            self.fail(f'{what} has no uri')
        try:
            if '://' in uri or self.base_dir is None:
                return confined_path(uri, self.package_share)
        except PackageFileError as error:
            self.fail(f'{what}: {error}', Reason.NO_RESOURCE)
        shown = quoted(uri)
        if os.path.isabs(uri) or '..' in uri.split('/') or '\0' in uri:
            self.fail(f"{what} names {shown}: a file of the world's own folder, or a "
                      'package:// uri', Reason.NO_RESOURCE)
        path = os.path.realpath(os.path.join(self.base_dir, uri))
        if not within(path, self.base_dir) or not os.path.isfile(path):
            self.fail(f"{what} names {shown}, which is no file in the world's folder",
                      Reason.NO_RESOURCE)
        return path

    def named_pose(self, element):
        name = self.name(element.get('name') or '', 'named pose name')
        description, tags = '', []
        position, orientation = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
        bounds_type, points = '', ()
        for child in element:
            if not isinstance(child.tag, str):
                continue
            if child.tag == 'description':
                description = self.text(child)
            elif child.tag == 'tag':
                tags.append(self.name(child.text or '', 'tag'))
            elif child.tag == 'origin':
                position, orientation = self.origin(child)
            elif child.tag == 'bounds':
                bounds_type, points = self.bounds(child, name)
            else:
                self.unsupported.append(f'<{child.tag[:40]}> in <named_pose>')
        if len(tags) > MAX_ENTRIES:
            self.fail(f'named pose {quoted(name)} has more than {MAX_ENTRIES} tags')
        return NamedPose(name, description, tuple(dict.fromkeys(tags)), position, orientation,
                         bounds_type, points)

    def origin(self, element):
        xyz = self.numbers(element.get('xyz', '0 0 0'), 3, 'origin xyz')
        rpy = self.numbers(element.get('rpy', '0 0 0'), 3, 'origin rpy')
        quaternion = np.zeros(4)
        mujoco.mju_euler2Quat(quaternion, np.array(rpy), 'XYZ')  # URDF's fixed axes
        return xyz, tuple(float(value) for value in quaternion)

    def bounds(self, element, pose):
        kind = element.get('type', '')
        if kind == 'box':
            lower = self.numbers(element.get('min', ''), 3, f'bounds min of {quoted(pose)}')
            upper = self.numbers(element.get('max', ''), 3, f'bounds max of {quoted(pose)}')
            if not all(low < high for low, high in zip(lower, upper)):
                self.fail(f'bounds of {quoted(pose)}: min must be below max on every axis')
            return kind, (lower, upper)
        if kind == 'sphere':
            centre = self.numbers(element.get('center', ''), 3,
                                  f'bounds center of {quoted(pose)}')
            radius, = self.numbers(element.get('radius', ''), 1,
                                   f'bounds radius of {quoted(pose)}')
            if not radius > 0.0:
                self.fail(f'bounds radius of {quoted(pose)} must be positive: {radius}')
            return kind, (centre, (radius, 0.0, 0.0))
        self.fail(f'bounds of {quoted(pose)} have type {quoted(kind)}: box or sphere')

    def numbers(self, text, count, what):
        values = parse_numbers(text[:1000], what)
        if len(values) != count:
            self.fail(f'{what} must be {count} numbers: {quoted(text)}')
        if any(abs(value) > MAX_COORDINATE for value in values):
            self.fail(f'{what} is beyond {MAX_COORDINATE:g} m: {quoted(text)}')
        return tuple(values)

    def model(self, element, poses):
        name = element.get('name', '')
        if name:
            try:
                check_model_name(name)
            except WorldError as error:
                self.fail(f'<model>: {error}')
        path = self.file(element.get('uri'), f'<model> {quoted(name)}')
        pose_name = element.get('pose')
        origin = element.find('origin')
        if pose_name is not None and origin is not None:
            self.fail(f'<model> {quoted(name)} has both a pose and an <origin>')
        if pose_name is not None:
            if pose_name not in poses:
                self.fail(f'<model> {quoted(name)} stands at pose {quoted(pose_name)}, which '
                          'the world does not name')
            pose = poses[pose_name]
            position, orientation = pose.position, pose.orientation
        elif origin is not None:
            position, orientation = self.origin(origin)
        else:
            position, orientation = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
        return StartModel(name=name, path=path, namespace=element.get('namespace', ''),
                          position=position, orientation=orientation)
