"""
An SDF model built as a MuJoCo spec: a RobotDescription the world spawns as it spawns a URDF's.

Each link is a body, posed relative to its parent link as the model frame has them; a joint's
child link hangs from its parent link. Revolute and continuous joints are hinges, prismatic
joints slides, ball joints balls, universal and revolute2 joints two hinges at one point, fixed
joints weld the child to its parent; a joint to the world anchors the model there. A model's
links make one tree: links that are free of each other (no joint between them) are refused
unless the model is static, when every link is welded where it stands. Inertials, shapes,
surface friction, colours (Gazebo's material scripts by name) and a link's gravity are built as
the URDF builder builds them, its mesh files read by meshes.py; links of one model collide with
each other only if both self-collide. The model's <plugin>s and its links' <sensor>s are
configured and built as a URDF's are (plugins.configure_plugins), unless the model is a
world's scenery, where they are named as not simulated; the model's top <pose> gives way to the
spawn pose, as ros_gz_sim's create has it.
"""

import dataclasses

import mujoco
import numpy as np

from service_tutorial.sim import frames
from service_tutorial.sim import plugins
from service_tutorial.sim.description import COLLISION_GROUP, UrdfError, VISUAL_GROUP
from service_tutorial.sim.description import OutlineElement, RobotOutline
from service_tutorial.sim.sdf.paths import SdfPaths
from service_tutorial.sim.sdf.poses import IDENTITY, relative, WORLD_FRAME
from service_tutorial.sim.sdf.reader import NO_LIMIT, parse_sdf, SdfReading
from service_tutorial.sim.urdf.builder import COLLISION_RGBA, CONTACT_TIME_CONSTANT
from service_tutorial.sim.urdf.builder import DEFAULT_VISUAL_RGBA, keep_links_apart
from service_tutorial.sim.urdf.builder import RobotDescription
from service_tutorial.sim.urdf.meshes import MeshLoader
from service_tutorial.sim.validation import DescriptionError, quoted, Reason

# How many elements a note names before it counts the rest.
NAMED_IN_NOTE = 20
_SHAPE_TYPES = {'box': mujoco.mjtGeom.mjGEOM_BOX, 'sphere': mujoco.mjtGeom.mjGEOM_SPHERE,
                'cylinder': mujoco.mjtGeom.mjGEOM_CYLINDER,
                'capsule': mujoco.mjtGeom.mjGEOM_CAPSULE,
                'ellipsoid': mujoco.mjtGeom.mjGEOM_ELLIPSOID,
                'plane': mujoco.mjtGeom.mjGEOM_PLANE, 'mesh': mujoco.mjtGeom.mjGEOM_MESH}


def load_sdf(text, *, base_dir=None, package_resolver=None, read_file, paths=None,
             timestep=0.002):
    """
    Build the RobotDescription of an SDF model's text, or raise DescriptionError naming why.

    base_dir: the folder of the file the text came from (None: a text); read_file(path, what)
    reads an included file; paths: the SdfPaths to resolve uris with (made if None); timestep:
    of the world the model goes to, which its plugins tune their actuators for.
    """
    reading = SdfReading(paths or SdfPaths(package_resolver), read_file)
    root, version = parse_sdf(text, 'SDF')
    found = [child for child in root if isinstance(child.tag, str)]
    if [child.tag for child in found] != ['model']:
        if any(child.tag == 'world' for child in found):
            raise DescriptionError('SDF holds a <world>, not a model to spawn: load it as a '
                                   'world (LoadWorld)', Reason.UNSUPPORTED_FORMAT)
        raise DescriptionError(f'SDF must hold one <model> to spawn, not '
                               f'{", ".join(f"<{child.tag}>" for child in found) or "none"}')
    model = reading.model(found[0], version, base_dir)
    return build(model, package_resolver, notes=reading.notes, files=reading.files,
                 ignored_plugins=reading.ignored_plugins, timestep=timestep)


def build(model, package_resolver, *, scenery=False, notes=(), files=(), ignored_plugins=(),
          timestep=0.002):
    """
    Return the RobotDescription of an SdfModel.

    scenery: the model is part of a world's scenery, where planes may be and plugins are not
    simulated; notes: what its file holds that is not simulated, ignored_plugins the filenames
    of the <plugin>s among it; files: the files it was read from (includes); timestep: of the
    world the model goes to.
    """
    description = _SpecBuilder(model, package_resolver, scenery).build(notes, files)
    blocks = model.plugins + tuple(block for link in model.links for block in link.sensors)
    if scenery or not blocks:
        return dataclasses.replace(description, ignored_plugins=tuple(ignored_plugins))
    outline = RobotOutline(
        name=model.name, links=tuple(OutlineElement(link.name) for link in model.links),
        joints=tuple(OutlineElement(joint.name, joint.kind) for joint in model.joints))
    try:
        setups, plugin_notes = plugins.configure_plugins(blocks, outline)
        for setup in setups:
            plugins.plugin_class(setup.kind).build(description.spec, setup.config, timestep)
    except UrdfError as error:
        raise DescriptionError(f'model {quoted(model.name)}: {error}') from None
    return dataclasses.replace(
        description, plugins=setups, ignored_plugins=tuple(ignored_plugins),
        actuators=tuple(actuator.name for actuator in description.spec.actuators),
        notes=tuple(plugin_notes) + description.notes)


def note_of(notes):
    """Return the one note that names what a file holds and the world does not simulate."""
    notes = list(notes)
    if not notes:
        return None
    more = f' and {len(notes) - NAMED_IN_NOTE} more' if len(notes) > NAMED_IN_NOTE else ''
    return f'not simulated, ignored: {"; ".join(notes[:NAMED_IN_NOTE])}{more}'


class _SpecBuilder:
    """Adds a body for every link of an SdfModel to a new spec."""

    def __init__(self, model, package_resolver, scenery):
        self._model = model
        self._scenery = scenery
        self._links = {link.name: link for link in model.links}
        self._spec = mujoco.MjSpec()
        self._spec.compiler.degree = False
        self._spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
        self._spec.strippath = False
        self._meshes = MeshLoader(self._spec, None, package_resolver)
        self._collides = []  # (link, self_collide) of every link with a collision geom
        self._weld = {}  # link -> the root of its rigid group (None: the world)
        self._weld_parent = {}  # group root -> the group its parent belongs to
        self._joint_names = []

    def build(self, not_simulated, files):
        """Return the RobotDescription of the model."""
        model = self._model
        if len(self._links) != len(model.links):
            raise DescriptionError(f'model {quoted(model.name)} has two links of one name')
        if model.static:
            root, anchored = self._static_tree()
        else:
            root, anchored = self._moving_tree()
        keep_links_apart(self._spec, self._collides, self._weld, self._weld_parent)
        missing = _unique(self._meshes.missing)
        notes = [f'mesh {quoted(uri)} cannot be had, so it is left out: {reason}'
                 for uri, reason in missing] + self._meshes.left_out
        note = note_of(not_simulated)
        if note:
            notes.append(note)
        root_link = self._links[root]
        return RobotDescription(
            robot_name=model.name, spec=self._spec, root_link=root, anchored=anchored,
            root_position=tuple(root_link.pose[0]), root_orientation=tuple(root_link.pose[1]),
            links=tuple(self._links), joints=tuple(self._joint_names),
            mesh_files=tuple(self._meshes.files), missing_meshes=tuple(uri for uri, _ in missing),
            notes=tuple(notes), source_files=tuple(dict.fromkeys(files)))

    def _static_tree(self):
        """Weld every link of a static model to its canonical link, where it stands."""
        root = self._model.canonical_link
        root_body = self._body(self._spec.worldbody, root, None)
        for name in self._links:
            if name != root:
                self._body(root_body, name, root)
        for name in self._links:
            self._weld[name] = None
        return root, True

    def _moving_tree(self):
        """Build the tree of links the joints make; return (root link, anchored)."""
        model = self._model
        parent_joint, children = {}, {}
        for joint in model.joints:
            if joint.child in parent_joint:
                raise DescriptionError(f'link {quoted(joint.child)} of model '
                                       f'{quoted(model.name)} is the child of two joints: '
                                       f'{quoted(parent_joint[joint.child].name)} and '
                                       f'{quoted(joint.name)}')
            parent_joint[joint.child] = joint
            children.setdefault(joint.parent, []).append(joint)
        roots = [name for name in self._links if name not in parent_joint
                 or parent_joint[name].parent == WORLD_FRAME]
        if len(roots) != 1:
            named = ', '.join(quoted(name) for name in roots[:5]) or 'none'
            raise DescriptionError(
                f'model {quoted(model.name)} has {len(roots)} links free of each other '
                f'({named}): the world spawns a model that moves as one tree of links joined '
                'by joints, or a static one', Reason.UNSUPPORTED_CONTENT
                if roots else Reason.NOT_PARSEABLE)
        root = roots[0]
        world_joint = parent_joint.get(root)
        root_body = self._body(self._spec.worldbody, root, None)
        if world_joint is None:
            root_body.add_freejoint()
        elif world_joint.kind != 'fixed':
            self._add_joint(root_body, world_joint)
        moves = world_joint is None or world_joint.kind != 'fixed'
        self._weld[root] = root if moves else None
        self._weld_parent[root] = None
        reached = {root}
        stack = [(root_body, joint) for joint in reversed(children.get(root, []))]
        while stack:
            parent_body, joint = stack.pop()
            if joint.child in reached:
                raise DescriptionError(f'the joints of model {quoted(model.name)} form a loop '
                                       f'at link {quoted(joint.child)}')
            reached.add(joint.child)
            body = self._body(parent_body, joint.child, joint.parent)
            if joint.kind == 'fixed':
                self._weld[joint.child] = self._weld[joint.parent]
            else:
                self._add_joint(body, joint)
                self._weld[joint.child] = joint.child
                self._weld_parent[joint.child] = self._weld[joint.parent]
            stack.extend((body, child) for child in reversed(children.get(joint.child, [])))
        unreached = [name for name in self._links if name not in reached]
        if unreached:
            raise DescriptionError(f'the joints of model {quoted(model.name)} form a loop: '
                                   f'links {", ".join(map(quoted, unreached[:5]))} are not '
                                   f'reached from {quoted(root)}')
        return root, world_joint is not None

    def _body(self, parent_body, name, parent_link):
        """Add a link's body under its parent's, posed as the model frame has them."""
        link = self._links[name]
        # The root body stands at the spawn pose; its pose in the model frame is root_position.
        pose = IDENTITY if parent_link is None else relative(self._links[parent_link].pose,
                                                             link.pose)
        # Fields are set on each new element: add_body(name=..., pos=...) and the other
        # add_*() cost MuJoCo's bindings several microseconds more per element.
        body = parent_body.add_body()
        body.name, body.pos, body.quat = name, pose[0], pose[1]
        self._set_inertia(body, link)
        if not link.gravity:
            body.gravcomp = 1.0  # MuJoCo's gravity compensation holds the body's weight
        for shape in link.visuals:
            geom = self._add_geom(body, shape, name, collision=False)
            if geom is not None:
                geom.contype = geom.conaffinity = 0
                geom.group = VISUAL_GROUP
                geom.rgba = shape.rgba if shape.rgba is not None else DEFAULT_VISUAL_RGBA
        for shape in link.collisions:
            geom = self._add_geom(body, shape, name, collision=True)
            if geom is None:
                continue
            geom.group = COLLISION_GROUP
            geom.rgba = COLLISION_RGBA
            geom.solref = [CONTACT_TIME_CONSTANT, 1.0]
            if shape.friction is not None:
                # ODE takes the smaller friction of two surfaces; MuJoCo the higher-priority
                # geom's, so the model's own setting wins over the floor's.
                geom.priority = 1
                geom.friction[0] = shape.friction
                if shape.friction == 0.0:
                    geom.condim = 1
            if not self._collides or self._collides[-1][0] != name:
                self._collides.append((name, link.self_collide))
        return body

    def _set_inertia(self, body, link):
        body.explicitinertial = True
        if self._model.static:
            body.mass, body.inertia = 0.0, [0.0, 0.0, 0.0]
            return
        moments, principal = frames.principal_inertia(link.inertial_pose[1], link.inertia)
        if not moments[-1] > 0.0:
            raise DescriptionError(f'link {quoted(link.name)} of model '
                                   f'{quoted(self._model.name)} has an inertia that is not '
                                   f'positive definite (principal moments {moments.tolist()})')
        body.mass = link.mass
        body.ipos = link.inertial_pose[0]
        body.iquat = principal
        body.inertia = moments

    def _add_geom(self, body, shape, link_name, *, collision):
        """Add a shape to a link's body; return the geom, or None if it is left out."""
        what = f'{"collision" if collision else "visual"} {quoted(shape.name)} of link ' \
            f'{quoted(link_name)}'
        kind = _SHAPE_TYPES[shape.kind]
        geom_fields = {'type': kind, 'pos': shape.pose[0], 'quat': shape.pose[1]}
        if shape.kind == 'mesh':
            if not shape.path:
                self._meshes.missing.append((shape.uri, shape.missing))
                return None
            try:
                mesh = self._meshes.add_file(shape.path, shape.uri, shape.scale, what,
                                             collision=collision)
            except UrdfError as error:
                raise DescriptionError(str(error)) from None
            if mesh is None:
                return None
            geom_fields['meshname'] = mesh
        elif shape.kind == 'plane':
            if not self._scenery:
                raise DescriptionError(f'{what} is a plane, which only a world may have',
                                       Reason.UNSUPPORTED_CONTENT)
            turn = np.zeros(4)
            mujoco.mju_quatZ2Vec(turn, np.array(shape.normal))
            geom_fields['quat'] = frames.compose(np.zeros(3), shape.pose[1], np.zeros(3),
                                                 turn)[1]
            geom_fields['size'] = [shape.size[0] / 2.0, shape.size[1] / 2.0, 0.05]
        else:
            geom_fields['size'] = _mujoco_size(shape.kind, shape.size)
        geom = body.add_geom()
        for field, value in geom_fields.items():
            setattr(geom, field, value)
        return geom

    def _add_joint(self, body, joint):
        """Add a joint's MuJoCo joints to its child's body, in the child's frame."""
        child_pose = self._links[joint.child].pose
        position = relative(child_pose, joint.pose)[0]
        if joint.kind == 'ball':
            ball = body.add_joint()
            ball.name, ball.type, ball.pos = joint.name, mujoco.mjtJoint.mjJNT_BALL, position
            self._joint_names.append(joint.name)
            return
        kind = mujoco.mjtJoint.mjJNT_SLIDE if joint.kind == 'prismatic' else \
            mujoco.mjtJoint.mjJNT_HINGE
        for index, axis in enumerate(joint.axes):
            name = joint.name if index == 0 else f'{joint.name}_axis2'
            mj_joint = body.add_joint()
            mj_joint.name, mj_joint.type, mj_joint.pos = name, kind, position
            mj_joint.axis = frames.rotate_back(child_pose[1], axis.xyz)
            bounded = abs(axis.lower) < NO_LIMIT and abs(axis.upper) < NO_LIMIT
            if joint.kind != 'continuous' and bounded:
                if not axis.lower < axis.upper:
                    raise DescriptionError(f'joint {quoted(joint.name)} limit lower '
                                           f'{axis.lower:g} is not below upper {axis.upper:g}')
                mj_joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
                mj_joint.range = [axis.lower, axis.upper]
            else:
                mj_joint.limited = mujoco.mjtLimited.mjLIMITED_FALSE
            if 0.0 < axis.effort < NO_LIMIT:
                mj_joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
                mj_joint.actfrcrange = [-axis.effort, axis.effort]
            mj_joint.damping = [axis.damping] + [0.0] * (len(mj_joint.damping) - 1)
            mj_joint.frictionloss = axis.friction
            mj_joint.stiffness = [axis.spring_stiffness] + [0.0] * (len(mj_joint.stiffness) - 1)
            mj_joint.springref = axis.spring_reference
            self._joint_names.append(name)


def _mujoco_size(kind, size):
    """Return MuJoCo's size of an SDF shape: half extents and radii."""
    if kind == 'box':
        return [value / 2.0 for value in size]
    if kind in ('cylinder', 'capsule'):
        return [size[0], size[1] / 2.0, 0.0]
    if kind == 'sphere':
        return [size[0], 0.0, 0.0]
    return list(size)  # an ellipsoid's radii


def _unique(pairs):
    """Return (name, reason) pairs with each name once, in the order first met."""
    first = {}
    for name, reason in pairs:
        first.setdefault(name, reason)
    return list(first.items())
