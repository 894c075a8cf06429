"""
SDF text read into models whose every link, joint and axis is posed in the model's frame.

The reader takes SDF 1.4 to 1.11, each file by its own <sdf version>, as sdformat converts it:
poses and frames as poses.py resolves them, nested models and <include>s flattened into their
top model with scoped names (nested::link), joint axes in the frame SDF says (1.4: the model
frame; 1.5 and 1.6: the joint frame unless use_parent_model_frame; 1.7 on: the joint frame
unless expressed_in). An <include> reads the model of a folder (its model.config picks the
file) or of a file, by the uri rules of paths.py, through the caller's reader of robot files
(read_file), each file once per reading; a cycle of includes, nesting deeper than MAX_NESTING
or more than MAX_INCLUDES includes are refused, naming them. What the world does not simulate
is named in the reading's notes (elements.py). A model's <plugin>s are kept as blocks
(urdf/gazebo.py) for the plugins the world simulates (gz-sim's systems, Gazebo Classic's
plugins); one of no kind the world simulates, or of a nested model, is named instead.
"""

import dataclasses
from dataclasses import dataclass
import os

from lxml import etree

import numpy as np

from service_tutorial.sim import frames
from service_tutorial.sim.plugins import kind_of
from service_tutorial.sim.sdf.elements import boolean, child_text, name_of, Notes, number
from service_tutorial.sim.sdf.elements import first_child, numbers
from service_tutorial.sim.sdf.links import LinkReader
from service_tutorial.sim.sdf.paths import built_in, MODEL_CONFIG, model_file
from service_tutorial.sim.sdf.paths import NEWEST_VERSION, parse_version
from service_tutorial.sim.sdf.paths import UriMissing, UriRefused
from service_tutorial.sim.sdf.poses import compose, FrameGraph, inverse
from service_tutorial.sim.sdf.poses import read_pose, SCOPE, WORLD_FRAME
from service_tutorial.sim.urdf.gazebo import plugin_block
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES, parse_xml
from service_tutorial.sim.validation import AssetError, DescriptionError, quoted, Reason

OLDEST_VERSION = (1, 4)
MAX_NESTING = 16  # models within models, includes counted
MAX_INCLUDES = 1000  # of one reading, the same file as often as it is included
JOINT_TYPES = ('continuous', 'revolute', 'prismatic', 'fixed', 'ball', 'universal',
               'revolute2', 'screw', 'gearbox')
NOT_SIMULATED_JOINTS = ('screw', 'gearbox')
AXES = {'revolute': ('axis',), 'continuous': ('axis',), 'prismatic': ('axis',),
        'universal': ('axis', 'axis2'), 'revolute2': ('axis', 'axis2')}
# Limits SDF 1.9 and older write for "none".
NO_LIMIT = 1e15


@dataclass(frozen=True)
class Axis:
    """A joint axis: its direction in the model frame, limits and dynamics."""

    xyz: np.ndarray  # unit vector in the model frame
    lower: float = -np.inf
    upper: float = np.inf
    effort: float = np.inf
    damping: float = 0.0
    friction: float = 0.0
    spring_reference: float = 0.0
    spring_stiffness: float = 0.0


@dataclass(frozen=True)
class Joint:
    """A joint between two links (the parent may be 'world'), posed in the model frame."""

    name: str
    kind: str
    parent: str
    child: str
    pose: tuple
    axes: tuple = ()


@dataclass(frozen=True)
class SdfModel:
    """A model read: its links and joints in its frame, and where its text came from."""

    name: str
    static: bool
    pose: tuple  # of its model frame, in its parent's frame
    relative_to: str  # the frame of its parent that pose is given in ('' for the default)
    links: tuple
    joints: tuple
    canonical_link: str
    plugins: tuple  # urdf.gazebo.PluginBlocks of its own <plugin>s of a simulated kind
    element: object  # the <model> it was read from (an include's target)
    version: tuple  # of the file that holds element
    base_dir: str  # that file's folder (None for a text)
    graph: FrameGraph = dataclasses.field(default=None, compare=False)  # its frames


def parse_sdf(text, what):
    """Return (root, version) of SDF text, or refuse it naming what it is."""
    data = text.encode('utf-8') if isinstance(text, str) else bytes(text)
    if len(data) > MAX_MODEL_XML_BYTES:
        raise DescriptionError(f'{what} is {len(data)} bytes, more than the limit of '
                               f'{MAX_MODEL_XML_BYTES}')
    try:
        root = parse_xml(data, what)
    except ValueError as error:
        raise DescriptionError(str(error)) from None
    tag = root.tag if isinstance(root.tag, str) else ''
    if tag != 'sdf':
        raise DescriptionError(f'{what} is not SDF: its root element is <{tag[:40]}>',
                               Reason.UNSUPPORTED_FORMAT)
    try:
        version = parse_version(root.get('version'), f'{what} <sdf>')
    except ValueError as error:
        raise DescriptionError(str(error)) from None
    if not OLDEST_VERSION <= version <= NEWEST_VERSION:
        raise DescriptionError(
            f'{what} is SDF {version[0]}.{version[1]}; the world reads SDF '
            f'{OLDEST_VERSION[0]}.{OLDEST_VERSION[1]} to {NEWEST_VERSION[0]}.'
            f'{NEWEST_VERSION[1]}', Reason.UNSUPPORTED_FORMAT)
    return root, version


class SdfReading:
    """One reading of an SDF file and every file it includes, with the notes it makes."""

    def __init__(self, paths, read_file):
        """Find uris with paths (SdfPaths); read files with read_file(path, what) -> text."""
        self.paths = paths
        self.read_file = read_file
        self.notes = Notes()
        self.ignored_plugins = []  # filenames of the <plugin>s not simulated, once each
        self.includes = 0
        self.files = []  # real paths of the files read, includes and model.config
        self._parsed = {}  # real path -> (root, version)
        self._stack = []  # the files being read, outermost first

    def model(self, element, version, base_dir, *, name=None, static=None, depth=0,
              scope=''):
        """Return the SdfModel of a <model>, under name and static if an include says so."""
        name = name or name_of(element, scope or 'the SDF')
        shown = f'model {quoted(scope + name)}'
        if depth > MAX_NESTING:
            raise DescriptionError(f'{shown} is nested more than {MAX_NESTING} deep')
        self.notes.children(element, 'model', shown)
        static = boolean(element, 'static', False, shown) if static is None else static
        self_collide = boolean(element, 'self_collide', False, shown)
        graph = FrameGraph(name, shown)
        links, joints, nested, plugins = [], [], [], []
        for child in element:
            tag = child.tag if isinstance(child.tag, str) else ''
            if tag in ('link', 'joint', 'frame'):
                child_name = name_of(child, shown)
                pose, relative_to = read_pose(first_child(child, 'pose'), version,
                                              f'{tag} {quoted(child_name)} of {shown}')
                attached_to = child.get('attached_to', '') if tag == 'frame' else \
                    (child_text(child, 'child') or '') if tag == 'joint' else ''
                graph.add(tag, child_name, pose, relative_to, attached_to)
                (links if tag == 'link' else joints if tag == 'joint' else []).append(child)
            elif tag in ('model', 'include'):
                inner = self._nested(child, version, base_dir, depth, scope + name + SCOPE,
                                     shown)
                if inner is not None:
                    model, pose, relative_to = inner
                    graph.add('model', model.name, pose, relative_to)
                    graph.nest(model.name, model.graph)
                    nested.append(model)
            elif tag == 'plugin':
                block = plugin_block(child)
                if kind_of(block.filename) is None:
                    self.ignore_plugin(block.filename, shown)
                else:
                    plugins.append(block)
        graph.canonical_link = self._canonical(element, graph, nested, version, shown)
        reader = LinkReader(self, graph, version, base_dir, static)
        all_links = [reader.link(link, self_collide) for link in links]
        all_joints = [self._joint(joint, graph, version, shown) for joint in joints]
        graph.check()
        for model in nested:
            frame = graph.pose(model.name)
            if model.static and not static:
                self.notes.add('<static> of a model nested in a moving one (it moves with '
                               'it)', f'model {quoted(scope + name + SCOPE + model.name)}')
            all_links += [_moved_link(link, model.name, frame) for link in model.links]
            all_joints += [_moved_joint(joint, model.name, frame) for joint in model.joints]
            nested_name = quoted(scope + name + SCOPE + model.name)
            for block in model.plugins:  # its joints' names are its own: not simulated
                self.ignore_plugin(block.filename, f'nested model {nested_name}')
        return SdfModel(name=name, static=static, pose=None, relative_to='',
                        links=tuple(all_links), joints=tuple(all_joints),
                        canonical_link=graph.canonical_link, plugins=tuple(plugins),
                        element=element, version=version, base_dir=base_dir, graph=graph)

    def ignore_plugin(self, filename, owner):
        """Name a <plugin> the world does not simulate, of owner ("model 'm'")."""
        self.notes.add(f'<plugin> {quoted(filename)}', owner)
        if filename and filename not in self.ignored_plugins:
            self.ignored_plugins.append(filename)

    def placed(self, element, model, version, asker, *, pose_element=None):
        """
        Return (pose, relative_to) of a model's frame as an element places it.

        pose_element: the <pose> that places it (the model's own if None); a placement frame
        (the model's @placement_frame, an include's <placement_frame>) is what that pose
        places, from SDF 1.8.
        """
        pose_element = first_child(element, 'pose') if pose_element is None else pose_element
        pose, relative_to = read_pose(pose_element, version, asker)
        placement = element.get('placement_frame') or child_text(element, 'placement_frame')
        if placement and version >= (1, 8):
            pose = compose(pose, inverse(model.graph.pose(placement, asker)))
        return pose, relative_to

    def _nested(self, element, version, base_dir, depth, scope, shown):
        """Return (SdfModel, pose, relative_to) of a nested <model> or <include>, or None."""
        if element.tag == 'model':
            model = self.model(element, version, base_dir, depth=depth + 1, scope=scope)
            pose, relative_to = self.placed(element, model, version,
                                            f'model {quoted(model.name)} of {shown}')
            return model, pose, relative_to
        return self.include(element, version, base_dir, depth=depth + 1, scope=scope,
                            shown=shown)

    def include(self, element, version, base_dir, *, depth, scope, shown):
        """Return (SdfModel, pose, relative_to) of what an <include> includes, or None."""
        self.includes += 1
        if self.includes > MAX_INCLUDES:
            raise DescriptionError(f'{shown} has more than {MAX_INCLUDES} <include>s',
                                   Reason.UNSUPPORTED_CONTENT)
        self.notes.children(element, 'include', f'<include> of {shown}')
        uri = child_text(element, 'uri') or ''
        what = f'<include> {quoted(uri)} of {shown}'
        if not uri:
            raise DescriptionError(f'an <include> of {shown} has no <uri>')
        if (element.get('merge') or '').strip().lower() in ('true', '1'):
            raise DescriptionError(f'{what} merges its model, which the world does not do',
                                   Reason.UNSUPPORTED_CONTENT)
        if depth > MAX_NESTING:
            raise DescriptionError(f'{what} is nested more than {MAX_NESTING} deep')
        text = built_in(uri)
        if text is not None:
            path, root, file_version = None, *parse_sdf(text, what)
        else:
            path = self._model_path(uri, base_dir, what)
            if path in self._stack:
                chain = ' -> '.join(quoted(os.path.basename(file)) for file in
                                    self._stack[self._stack.index(path):] + [path])
                raise DescriptionError(f'{what} includes itself: {chain}',
                                       Reason.UNSUPPORTED_CONTENT)
            root, file_version = self._parsed_file(path, what)
        found = [child for child in root if isinstance(child.tag, str)]
        if len(found) != 1 or found[0].tag not in ('model', 'light', 'actor'):
            raise DescriptionError(f'{what} must hold one <model>, <light> or <actor>, not '
                                   f'{", ".join(f"<{child.tag}>" for child in found) or "none"}')
        if found[0].tag != 'model':
            if found[0].tag == 'actor':
                self.notes.add('<actor>', what)
            return None  # a light has no physics effect: the Sun
        self._stack.append(path)
        try:
            static = boolean(element, 'static', None, what)
            model = self.model(found[0], file_version,
                               os.path.dirname(path) if path else None,
                               name=child_text(element, 'name') or None, static=static,
                               depth=depth, scope=scope)
        finally:
            self._stack.pop()
        own_pose = first_child(element, 'pose')
        if own_pose is None:  # the model's own pose, with no frame of the including scope
            pose, _ = self.placed(found[0], model, file_version, what)
            return model, pose, ''
        pose, relative_to = self.placed(element, model, version, what, pose_element=own_pose)
        return model, pose, relative_to

    def _model_path(self, uri, base_dir, what):
        """Return the real path of the SDF file an include's uri names."""
        try:
            path = self.paths.locate(uri, base_dir, what)
        except UriRefused as refused:
            raise AssetError(str(refused)) from None
        except UriMissing as missing:
            raise AssetError(f'{missing}; a model an <include> names must be there',
                             missing=True) from None
        if os.path.isdir(path):
            config = os.path.join(path, MODEL_CONFIG)
            if not os.path.isfile(config):
                raise AssetError(f'{what} names the folder {quoted(path)}, which has no '
                                 f'{MODEL_CONFIG}', missing=True)
            self.files.append(config)
            try:
                path = model_file(path, self.read_file(config, f'{MODEL_CONFIG} of {what}'))
            except UriRefused as refused:
                raise AssetError(str(refused)) from None
            if not os.path.isfile(path):
                raise AssetError(f'{what}: {MODEL_CONFIG} names {quoted(path)}, which is not '
                                 'there', missing=True)
        return path

    def _parsed_file(self, path, what):
        """Return (root, version) of an SDF file, read and parsed once per reading."""
        if path not in self._parsed:
            self.files.append(path)
            self._parsed[path] = parse_sdf(self.read_file(path, what), f'{what} ({path})')
        return self._parsed[path]

    def _canonical(self, element, graph, nested, version, shown):
        """Return the (scoped) link the model frame is attached to."""
        named = element.get('canonical_link') if version >= (1, 7) else None
        if named:
            if graph.kind(named) != 'link' and not (SCOPE in named and graph.has(named)):
                raise DescriptionError(f'{shown} canonical_link {quoted(named)} is no link of '
                                       'it')
            return named
        if graph.links:
            return graph.links[0]
        if nested:
            return nested[0].name + SCOPE + nested[0].canonical_link
        raise DescriptionError(f'{shown} has no link; a model has at least one')

    def _joint(self, element, graph, version, shown):
        """Return the Joint of a <joint>, its ends resolved to links."""
        name = element.get('name')
        what = f'joint {quoted(name)} of {shown}'
        self.notes.children(element, 'joint', what)
        kind = element.get('type', '')
        if kind not in JOINT_TYPES:
            raise DescriptionError(f'{what} has type {quoted(kind)}, none of '
                                   f'{", ".join(JOINT_TYPES)}')
        if kind in NOT_SIMULATED_JOINTS:
            raise DescriptionError(f'{what} is a {kind} joint, which the world does not '
                                   'simulate', Reason.UNSUPPORTED_CONTENT)
        ends = []
        for end in ('parent', 'child'):
            frame = child_text(element, end)
            if not frame:
                raise DescriptionError(f'{what} has no <{end}>')
            if frame == WORLD_FRAME:
                if end == 'child':
                    raise DescriptionError(f'{what} has the world as its child')
                ends.append(WORLD_FRAME)
            else:
                ends.append(graph.link_of(frame, f'{what} <{end}>'))
        if ends[0] == ends[1]:
            raise DescriptionError(f'{what} joins link {quoted(ends[0])} to itself')
        pose = graph.pose(name, what)
        axes = tuple(self._axis(first_child(element, tag), tag, graph, pose, version, what)
                     for tag in AXES.get(kind, ()))
        return Joint(name=name, kind=kind, parent=ends[0], child=ends[1], pose=pose, axes=axes)

    def _axis(self, element, tag, graph, joint_pose, version, what):
        """Return the Axis of a joint's <axis> or <axis2>, in the model frame."""
        shown = f'<{tag}> of {what}'
        if element is None:
            element = etree.Element(tag)  # SDF's defaults: 0 0 1, no limits
        self.notes.children(element, 'axis', shown)
        xyz_element = first_child(element, 'xyz')
        xyz = np.array(numbers(child_text(element, 'xyz') or '0 0 1', 3, f'{shown} <xyz>'))
        if not np.linalg.norm(xyz) > 1e-9:
            raise DescriptionError(f'{shown} <xyz> is zero')
        frame = joint_pose
        if version < (1, 5) or (version < (1, 7) and boolean(
                element, 'use_parent_model_frame', False, shown)):
            frame = (None, frames.IDENTITY_QUATERNION)
        elif version >= (1, 7) and xyz_element is not None and xyz_element.get('expressed_in'):
            frame = graph.pose(xyz_element.get('expressed_in'), shown)
        direction = frames.rotate(frame[1], xyz / np.linalg.norm(xyz))
        fields = {}
        limit = first_child(element, 'limit')
        if limit is not None:
            self.notes.children(limit, 'limit', shown)
            fields['lower'] = number(limit, 'lower', -np.inf, f'{shown} <limit>', infinite=True)
            fields['upper'] = number(limit, 'upper', np.inf, f'{shown} <limit>', infinite=True)
            effort = number(limit, 'effort', np.inf, f'{shown} <limit>', infinite=True)
            fields['effort'] = np.inf if effort < 0.0 else effort
            velocity = number(limit, 'velocity', np.inf, f'{shown} <limit>', infinite=True)
            if 0.0 <= velocity < NO_LIMIT:
                self.notes.add('<limit><velocity>', shown)
        dynamics = first_child(element, 'dynamics')
        if dynamics is not None:
            self.notes.children(dynamics, 'dynamics', shown)
            for key in ('damping', 'friction', 'spring_stiffness'):
                fields[key] = number(dynamics, key, 0.0, f'{shown} <dynamics>', minimum=0.0,
                                     maximum=1e12)
            fields['spring_reference'] = number(dynamics, 'spring_reference', 0.0,
                                                f'{shown} <dynamics>')
        return Axis(xyz=direction, **fields)


def _moved_link(link, scope, frame):
    """Return a nested model's link under its scoped name, posed in the outer model's frame."""
    return dataclasses.replace(link, name=scope + SCOPE + link.name,
                               pose=compose(frame, link.pose))


def _moved_joint(joint, scope, frame):
    """Return a nested model's joint under its scoped name, posed in the outer model's frame."""
    def scoped(end):
        return end if end == WORLD_FRAME else scope + SCOPE + end
    return Joint(name=scope + SCOPE + joint.name, kind=joint.kind, parent=scoped(joint.parent),
                 child=scoped(joint.child), pose=compose(frame, joint.pose),
                 axes=tuple(dataclasses.replace(axis, xyz=frames.rotate(frame[1], axis.xyz))
                            for axis in joint.axes))
