"""
SDF poses and the frames of a model, resolved as SDF 1.7 and later define them.

A <pose> is x y z roll pitch yaw (fixed axes, radians), or from SDF 1.9 in degrees or as a
quaternion x y z w; empty is the identity. Its relative_to names the frame it is given in;
without it, each element has its default: a link's is the model frame (__model__), a joint's
its child link, a <frame>'s the frame it is attached_to, a nested model's the model frame,
a collision's, visual's and inertial's its link. SDF 1.4 to 1.6 has the same defaults and no
relative_to; sdformat's conversion to 1.7 reads their pose@frame as relative_to, and so does
the reader. Names are those of the model's own links, joints, frames and models, and from
SDF 1.8 a nested model's frames by scope (a::b). A cycle of relative_to or attached_to, or a
name that is no frame, is refused with the element named.
"""

import math

import numpy as np

from service_tutorial.sim import frames
from service_tutorial.sim.sdf.elements import MAX_ANGLE, MAX_COORDINATE, numbers
from service_tutorial.sim.validation import DescriptionError, quoted

MODEL_FRAME = '__model__'
WORLD_FRAME = 'world'
SCOPE = '::'
IDENTITY = (np.zeros(3), np.array(frames.IDENTITY_QUATERNION))


def read_pose(element, version, what):
    """Return ((position, quaternion), relative_to) of a <pose> (None: the identity, '')."""
    if element is None:
        return IDENTITY, ''
    attribute = 'relative_to' if version >= (1, 7) else 'frame'
    relative_to = (element.get(attribute) or '').strip()
    text = (element.text or '').strip()
    shown = f'<pose> of {what}'
    if not text:
        return IDENTITY, relative_to
    if version >= (1, 9) and element.get('rotation_format', 'euler_rpy') == 'quat_xyzw':
        values = numbers(text, 7, shown, limit=MAX_COORDINATE)
        x, y, z, w = values[3:]
        quaternion = np.array([w, x, y, z])
        if not np.linalg.norm(quaternion) > 1e-9:
            raise DescriptionError(f'{shown} has a zero quaternion: {quoted(text)}')
        return (np.array(values[:3]), quaternion / np.linalg.norm(quaternion)), relative_to
    if version >= (1, 9) and element.get('rotation_format', 'euler_rpy') != 'euler_rpy':
        raise DescriptionError(f'{shown} has rotation_format '
                               f'{quoted(element.get("rotation_format"))}: euler_rpy or '
                               'quat_xyzw')
    values = numbers(text, 6, shown)
    if max(map(abs, values[:3])) > MAX_COORDINATE:
        raise DescriptionError(f'{shown} is absurd: its position is beyond '
                               f'{MAX_COORDINATE:g} m: {quoted(text)}')
    angles = values[3:]
    if version >= (1, 9) and (element.get('degrees') or '').strip().lower() in ('true', '1'):
        angles = list(map(math.radians, angles))
    if max(map(abs, angles)) > MAX_ANGLE:
        raise DescriptionError(f'{shown} is absurd: an angle is beyond {MAX_ANGLE:g} rad: '
                               f'{quoted(text)}')
    if not any(angles):  # most poses of a model turn nothing, and need no MuJoCo call
        return (np.array(values[:3]), np.array(frames.IDENTITY_QUATERNION)), relative_to
    return (np.array(values[:3]), frames.rpy_quaternion(angles)), relative_to


def compose(first, second):
    """Return the pose second (given in the frame of first) in first's parent."""
    return frames.compose(first[0], first[1], second[0], second[1])


def relative(frame, pose):
    """Return a pose given in a parent as seen from frame (given in the same parent)."""
    return frames.relative(frame[0], frame[1], pose[0], pose[1])


def inverse(pose):
    """Return the inverse of a pose."""
    return relative(pose, IDENTITY)


class FrameGraph:
    """The frames of one model scope, each posed relative to another, resolved on demand."""

    def __init__(self, model_name, what, root=MODEL_FRAME):
        """
        Start the scope of model_name (what names it in messages) with its root frame.

        root: the name of the frame poses are resolved in: the model frame, or for the frames of
        a world, 'world'.
        """
        self.model_name = model_name
        self.what = what
        self.root = root
        self._entries = {}  # name -> (kind, pose, relative_to, attached_to)
        self._nested = {}  # nested model name -> its FrameGraph
        self._resolved = {root: IDENTITY}
        self.links = []  # the scope's own links, in order
        self.canonical_link = ''  # set when the scope is complete

    def add(self, kind, name, pose, relative_to, attached_to=''):
        """
        Add a frame of kind ('link', 'joint', 'frame', 'model') with its pose.

        relative_to: the frame the pose is given in ('' for the kind's default, which
        attached_to gives: a joint's child, a frame's attached_to).
        """
        if name in self._entries or name == self.root or SCOPE in name:
            raise DescriptionError(f'{self.what} has two frames named {quoted(name)}'
                                   if name in self._entries else
                                   f'{self.what} has a {kind} named {quoted(name)}, which is '
                                   'not a name a frame may have')
        self._entries[name] = (kind, pose, relative_to or attached_to or self.root,
                               attached_to or self.root)
        if kind == 'link':
            self.links.append(name)

    def nest(self, name, graph):
        """Give the scope a nested model's frames, named name::<frame> from SDF 1.8."""
        self._nested[name] = graph

    def has(self, name):
        """Tell whether a name is a frame of the scope (scoped names included)."""
        if name == self.root or name in self._entries:
            return True
        model, separator, inner = name.partition(SCOPE)
        return bool(separator) and model in self._nested and self._nested[model].has(inner)

    def kind(self, name):
        """Return the kind of a frame of the scope itself, or None."""
        entry = self._entries.get(name)
        return entry[0] if entry else None

    def pose(self, name, asker=None, _chain=()):
        """Return the pose of a frame in the model frame; asker names who asks, for messages."""
        if name in self._resolved:
            return self._resolved[name]
        model, separator, inner = name.partition(SCOPE)
        if separator and model in self._nested:
            nested = self._nested[model]
            if not nested.has(inner):
                self._unknown(name, asker)
            return compose(self.pose(model, asker, _chain), nested.pose(inner, asker))
        if name not in self._entries:
            self._unknown(name, asker)
        if name in _chain:
            cycle = ' -> '.join(quoted(link) for link in _chain[_chain.index(name):] + (name,))
            raise DescriptionError(f'{self.what}: the poses of {cycle} are relative to each '
                                   'other in a cycle')
        kind, pose, relative_to, _ = self._entries[name]
        parent = self.pose(relative_to, f'{kind} {quoted(name)}', _chain + (name,))
        self._resolved[name] = compose(parent, pose)
        return self._resolved[name]

    def link_of(self, name, asker, _chain=()):
        """Return the (scoped) link a frame is attached to, as a joint's parent or child names."""
        if name == self.root:
            return self.canonical_link
        model, separator, inner = name.partition(SCOPE)
        if separator and model in self._nested and self._nested[model].has(inner):
            return model + SCOPE + self._nested[model].link_of(inner, asker)
        if name in self._nested:
            return name + SCOPE + self._nested[name].canonical_link
        entry = self._entries.get(name)
        if entry is None:
            self._unknown(name, asker)
        if name in _chain:
            raise DescriptionError(f'{self.what}: {asker} names {quoted(name)}, whose frames '
                                   'are attached to each other in a cycle')
        kind, _, _, attached_to = entry
        if kind == 'link':
            return name
        return self.link_of(attached_to, asker, _chain + (name,))

    def check(self):
        """Resolve every frame of the scope, as sdformat checks a model's frame graph."""
        for name, (kind, _, _, _) in self._entries.items():
            self.pose(name, f'{kind} {quoted(name)}')
            if kind == 'frame':
                self.link_of(name, f'frame {quoted(name)}')

    def _unknown(self, name, asker):
        raise DescriptionError(f'{self.what}: {asker or "a pose"} names the frame '
                               f'{quoted(name)}, which is no frame of model '
                               f'{quoted(self.model_name)}')
