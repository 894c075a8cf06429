"""
Turn URDF text into a MuJoCo MjSpec, with the plugins its <gazebo> blocks ask for.

The text goes through the hardened parser and structure checks of hardened_xml.py before
yourdfpy sees it; mesh files follow the path rules of meshes.py.
"""

import dataclasses
from dataclasses import dataclass
import io
import math

from lxml import etree
import mujoco
import numpy as np
from service_tutorial.sim import frames
from service_tutorial.sim import plugins
from service_tutorial.sim.description import COLLISION_GROUP, MAX_SIZE, VISUAL_GROUP
from service_tutorial.sim.description import parse_numbers
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.urdf.gazebo import gazebo_colour
from service_tutorial.sim.urdf.gazebo import LinkSettings
from service_tutorial.sim.urdf.gazebo import plugin_filenames
from service_tutorial.sim.urdf.gazebo import read_link_settings
from service_tutorial.sim.urdf.gazebo import read_plugin_blocks
from service_tutorial.sim.urdf.gazebo import read_sensor_plugin_blocks
from service_tutorial.sim.urdf.hardened_xml import check_structure
from service_tutorial.sim.urdf.hardened_xml import parse_model_xml
from service_tutorial.sim.urdf.meshes import MeshLoader
from service_tutorial.sim.urdf.origins import take_origins

WORLD_LINK = 'world'
DEFAULT_VISUAL_RGBA = (0.7, 0.7, 0.7, 1.0)
COLLISION_RGBA = (0.5, 0.2, 0.2, 0.5)
# Contact stiffness as a time constant (s). Stiffer than MuJoCo's 0.02 so that a wheel sinks
# only hundredths of a millimetre into the floor and rolls with its true radius.
CONTACT_TIME_CONSTANT = 0.005
DIFF_DRIVE = 'gazebo_ros_diff_drive'
NO_LINK_SETTINGS = LinkSettings()


@dataclass(frozen=True)
class RobotDescription:
    """
    A URDF robot built as a MuJoCo spec, ready to be attached to a world.

    Bodies, joints and actuators carry the URDF names; a world adds its own prefix.
    The root link gets a free joint, unless a URDF joint anchors it to a link named ``world``;
    then root_position/root_orientation hold that joint's origin, which the world applies.
    """

    robot_name: str
    spec: mujoco.MjSpec
    root_link: str
    anchored: bool
    root_position: tuple
    root_orientation: tuple
    links: tuple
    joints: tuple
    actuators: tuple = ()
    plugins: tuple = ()  # a plugins.PluginSetup for each <plugin> of a registered kind
    mesh_files: tuple = ()
    missing_meshes: tuple = ()  # mesh filenames as written that could not be had, left out
    ignored_plugins: tuple = ()  # <plugin> filenames of kinds not simulated here
    notes: tuple = ()  # what a user should know about how the robot was built, one line each
    source_files: tuple = ()  # the files besides its own it was read from (SDF's includes)

    def plugin_config(self, kind):
        """Return the configuration of the robot's first plugin of a kind, or None."""
        return next((setup.config for setup in self.plugins if setup.kind == kind), None)

    @property
    def diff_drive(self):
        """Return the DiffDriveConfig of the robot's diff-drive plugin, or None."""
        return self.plugin_config(DIFF_DRIVE)


def load_urdf(model_xml, *, base_dir=None, package_resolver=None, timestep=0.002):
    """
    Build a RobotDescription from URDF text, or raise UrdfError naming the problem.

    timestep is the physics timestep of the world the robot goes to; plugins tune their
    actuators (the wheel servos of a diff drive) for it.
    """
    root = parse_model_xml(model_xml)
    check_structure(root)
    # yourdfpy needs plain tags; namespaced extension elements play no part here.
    for element in [element for element in root.iter('*') if element.tag[0] == '{']:
        element.getparent().remove(element)
    origins = take_origins(root)
    # yourdfpy brings trimesh, a quarter of a second (a second with trimesh's extras, SciPy
    # and networkx, installed): imported by the first URDF built, so that a program that only
    # reads robot files (the lesson's clients) starts without.
    import yourdfpy
    try:
        urdf = yourdfpy.URDF.load(
            io.BytesIO(etree.tostring(root)), build_scene_graph=False,
            build_collision_scene_graph=False, load_meshes=False,
            load_collision_meshes=False)
    except Exception as error:
        raise UrdfError(f'model_xml is not valid URDF: {error}') from None
    if not urdf.validate():
        raise UrdfError(f'model_xml is not valid URDF: {urdf.errors[0].msg}')
    builder = _SpecBuilder(urdf.robot, origins, base_dir, package_resolver,
                           read_link_settings(root), timestep)
    description = builder.build()
    sensor_blocks, sensor_notes = read_sensor_plugin_blocks(root)
    setups, plugin_notes = plugins.configure_plugins(read_plugin_blocks(root) + sensor_blocks,
                                                     urdf.robot)
    for setup in setups:
        plugins.plugin_class(setup.kind).build(description.spec, setup.config, timestep)
    missing = _missing_meshes(root, builder.meshes.missing)
    ignored = _unique(filename for filename in plugin_filenames(root)
                      if filename and plugins.kind_of(filename) is None)
    notes = ([f"mesh '{filename}' cannot be had, so it is left out: {reason}"
              for filename, reason in missing]
             + builder.notes + [f"plugin '{filename}' is not simulated here; it is ignored"
                                for filename in ignored] + sensor_notes + plugin_notes)
    return dataclasses.replace(
        description, plugins=setups,
        actuators=tuple(actuator.name for actuator in description.spec.actuators),
        missing_meshes=tuple(filename for filename, _ in missing), ignored_plugins=ignored,
        notes=tuple(notes))


def _unique(items):
    """Return the items without repeats, in the order they first come."""
    return tuple(dict.fromkeys(items))


def _missing_meshes(root, missing):
    """Return (filename, reason) of each missing mesh once, in the order the URDF names them."""
    reasons = {}
    for filename, reason in missing:
        reasons.setdefault(filename, reason)
    written = _unique(mesh.get('filename') for mesh in root.iter('mesh'))
    return [(filename, reasons[filename]) for filename in written if filename in reasons]


def keep_links_apart(spec, collides, weld, weld_parent):
    """
    Keep a robot's links from colliding with each other, as Gazebo does.

    collides: (link name, self_collide) of every link with a collision geom; weld: per link,
    the link at the root of its rigid group (None: fixed to the world); weld_parent: per group
    root, the group its parent link belongs to (MuJoCo's welds). Two links of one model
    collide only if both self-collide. MuJoCo itself never lets links of one rigid group
    collide, nor two groups where one hangs from the other (unless that is the world): those
    pairs need no exclude, and every exclude costs each spawn and delete of the robot.
    """
    def kept_apart_by_mujoco(first, second):  # see mj_collision
        first, second = weld[first], weld[second]
        if first == second:
            return True
        if first is None or second is None:
            return False
        return first == weld_parent[second] or second == weld_parent[first]
    for index, (first, first_collides) in enumerate(collides):
        for second, second_collides in collides[index + 1:]:
            if not (first_collides and second_collides
                    or kept_apart_by_mujoco(first, second)):
                spec.add_exclude(bodyname1=first, bodyname2=second)


def check_size(size, count, what, across):
    """
    Refuse a shape's size that is not positive, or whose extents exceed MAX_SIZE.

    size: the shape's count numbers; across: what each number is multiplied by to give an
    extent (a radius by 2).
    """
    # Python floats, not numpy's calls: those cost more than the checks of these few
    # numbers, done for every shape of every spawn.
    values = size.tolist()
    if size.shape != (count,) or not all(0.0 < value < math.inf for value in values):
        raise UrdfError(f'{what} must be {count} positive numbers: {values}')
    extent = max(value * factor for value, factor in zip(values, across))
    if extent > MAX_SIZE:
        raise UrdfError(f'{what} {values}: the shape is {extent:g} m across, more '
                        f'than the limit of {MAX_SIZE:g} m')


def _finite(array):
    """Tell whether every number of a float array is finite."""
    # As Python floats: np.isfinite(array).all() costs twice as much, for each of the
    # origins, axes and inertias of every cold spawn.
    return all(map(math.isfinite, array.ravel().tolist()))


class _SpecBuilder:
    """Walks a yourdfpy robot from its root link and adds MuJoCo bodies for every link."""

    def __init__(self, robot, origins, base_dir, package_resolver, link_settings, timestep):
        self._robot = robot
        self._origins = origins  # from take_origins()
        self._link_settings = link_settings
        self._timestep = timestep
        masses = [float(link.inertial.mass) for link in robot.links
                  if link.inertial is not None and link.inertial.mass is not None]
        # Bad masses are refused link by link later; here they only must not spoil the sum.
        self._robot_mass = sum(mass for mass in masses if math.isfinite(mass) and mass > 0.0)
        self._robot_mass = min(self._robot_mass, 1e12) or 1.0
        self._links = {link.name: link for link in robot.links}
        self._materials = {material.name: material for material in robot.materials
                           if material.name}
        self._spec = mujoco.MjSpec()
        self._spec.compiler.degree = False
        self._spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
        self._spec.strippath = False
        self.meshes = MeshLoader(self._spec, base_dir, package_resolver)
        self.notes = []  # what the user should know about how the links were built
        self._collides = []  # (link name, selfCollide) of every link with a collision geom
        # Per link, the link at the root of its rigid group (None: fixed to the world), and
        # per group root, the group its parent link belongs to: MuJoCo's welds.
        self._weld = {}
        self._weld_parent = {}
        self._principal_inertias = {}  # (orientation, tensor bytes) -> principal_inertia()

    def build(self):
        """Return the finished spec and what a world needs to know about it."""
        robot = self._robot
        children = {}
        parent_joint = {}
        for joint in robot.joints:
            for end in (joint.parent, joint.child):
                if end not in self._links and end != WORLD_LINK:
                    raise UrdfError(f"joint '{joint.name}' names missing link '{end}'")
            if joint.child == WORLD_LINK:
                raise UrdfError(f"joint '{joint.name}' makes '{WORLD_LINK}' a child link")
            if joint.child in parent_joint:
                raise UrdfError(f"link '{joint.child}' is the child of two joints: "
                                f"'{parent_joint[joint.child].name}' and '{joint.name}'")
            if joint.type not in ('fixed', 'revolute', 'continuous', 'prismatic'):
                raise UrdfError(f"joint '{joint.name}' has type '{joint.type}', which is not "
                                'supported (use fixed, revolute, continuous or prismatic)')
            parent_joint[joint.child] = joint
            children.setdefault(joint.parent, []).append(joint)

        world_joints = children.get(WORLD_LINK, [])
        if len(world_joints) > 1:
            raise UrdfError(f"more than one joint attaches to the '{WORLD_LINK}' link")
        roots = [name for name in self._links if name != WORLD_LINK and (
            name not in parent_joint or parent_joint[name].parent == WORLD_LINK)]
        if not roots:
            if set(self._links) == {WORLD_LINK}:
                raise UrdfError(f"model_xml has no link besides '{WORLD_LINK}'")
            raise UrdfError('joints form a loop: every link is the child of a joint')
        if len(roots) > 1:
            raise UrdfError(f"model_xml has more than one root link: {', '.join(roots)}")
        root = roots[0]

        anchored = False
        root_position = (0.0, 0.0, 0.0)
        root_orientation = (1.0, 0.0, 0.0, 0.0)
        root_body = self._spec.worldbody.add_body()
        root_body.name = root
        if world_joints:
            world_joint = world_joints[0]
            position, orientation = self._pose(('joint', world_joint.name))
            root_position, root_orientation = tuple(position), tuple(orientation)
            anchored = True
            if world_joint.type != 'fixed':
                self._add_joint(root_body, world_joint)
        else:
            root_body.add_freejoint()
        moves = not anchored or world_joints[0].type != 'fixed'
        self._weld[root] = root if moves else None
        self._weld_parent[root] = None
        self._fill_link(root_body, root)

        visited = {root}
        joint_names = [joint.name for joint in world_joints if joint.type != 'fixed']
        stack = [(root_body, joint) for joint in reversed(children.get(root, []))]
        while stack:
            parent_body, joint = stack.pop()
            if joint.child in visited:
                raise UrdfError(f"joints form a loop at link '{joint.child}'")
            visited.add(joint.child)
            position, orientation = self._pose(('joint', joint.name))
            # Fields are set on the new element: add_body(name=..., pos=...) and the other
            # add_*() cost MuJoCo's bindings several microseconds more per element.
            body = parent_body.add_body()
            body.name, body.pos, body.quat = joint.child, position, orientation
            if joint.type != 'fixed':
                self._add_joint(body, joint)
                joint_names.append(joint.name)
                self._weld[joint.child] = joint.child
                self._weld_parent[joint.child] = self._weld[joint.parent]
            else:
                self._weld[joint.child] = self._weld[joint.parent]
            self._fill_link(body, joint.child)
            stack.extend((body, child) for child in reversed(children.get(joint.child, [])))
        unreached = [name for name in self._links if name not in visited and name != WORLD_LINK]
        if unreached:
            raise UrdfError(f"joints form a loop: links {', '.join(unreached)} are not "
                            f"reached from root link '{root}'")
        links = tuple(name for name in self._links if name != WORLD_LINK)
        self._keep_links_apart()
        self.notes.extend(self.meshes.left_out)
        return RobotDescription(
            robot_name=robot.name, spec=self._spec, root_link=root, anchored=anchored,
            root_position=root_position, root_orientation=root_orientation, links=links,
            joints=tuple(joint_names), mesh_files=tuple(self.meshes.files))

    def _add_joint(self, body, joint):
        axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
        if axis.shape != (3,) or not _finite(axis):
            raise UrdfError(f"joint '{joint.name}' axis is not three finite numbers")
        norm = np.linalg.norm(axis)
        if norm < 1e-9:
            raise UrdfError(f"joint '{joint.name}' axis is zero")
        kind = (mujoco.mjtJoint.mjJNT_SLIDE if joint.type == 'prismatic'
                else mujoco.mjtJoint.mjJNT_HINGE)
        mj_joint = body.add_joint()
        mj_joint.name, mj_joint.type, mj_joint.axis = joint.name, kind, axis / norm
        if joint.type in ('revolute', 'prismatic'):
            lower, upper = float(joint.limit.lower), float(joint.limit.upper)
            if not lower < upper:
                raise UrdfError(f"joint '{joint.name}' limit lower {lower} is not below "
                                f'upper {upper}')
            mj_joint.limited = mujoco.mjtLimited.mjLIMITED_TRUE
            mj_joint.range = [lower, upper]
        else:
            mj_joint.limited = mujoco.mjtLimited.mjLIMITED_FALSE
        if joint.dynamics is not None:
            for attribute, target in (('damping', 'damping'), ('friction', 'frictionloss')):
                text = getattr(joint.dynamics, attribute)
                if text is None:
                    continue
                value = parse_numbers(str(text), f"joint '{joint.name}' {attribute}")
                if len(value) != 1 or value[0] < 0.0:
                    raise UrdfError(f"joint '{joint.name}' {attribute} must be one number "
                                    f">= 0: '{text}'")
                if target == 'damping':
                    # The first coefficient is the linear one; the rest are higher orders.
                    mj_joint.damping = [value[0]] + [0.0] * (len(mj_joint.damping) - 1)
                else:
                    mj_joint.frictionloss = value[0]

    def _fill_link(self, body, link_name):
        link = self._links[link_name]
        settings = self._link_settings.get(link_name, NO_LINK_SETTINGS)
        self._set_inertia(body, link)
        if not settings.gravity:
            # MuJoCo's gravity compensation: a force that holds the body's weight.
            body.gravcomp = 1.0
        colour = self._gazebo_colour(settings.material, link_name)
        for index, visual in enumerate(link.visuals):
            geom = self._add_geom(body, visual.geometry, ('visual', link_name, index), link_name)
            if geom is None:
                continue
            geom.contype = 0
            geom.conaffinity = 0
            geom.group = VISUAL_GROUP
            geom.rgba = colour if colour is not None else self._visual_rgba(visual, link_name)
        solref = self._contact_solref(settings)
        for index, collision in enumerate(link.collisions):
            geom = self._add_geom(body, collision.geometry, ('collision', link_name, index),
                                  link_name, collision=True)
            if geom is None:
                continue
            geom.group = COLLISION_GROUP
            geom.rgba = COLLISION_RGBA
            geom.solref = solref
            if settings.mu is not None:
                # ODE combines the friction of two surfaces with min(); MuJoCo takes the
                # higher-priority geom's, so the link's own setting wins over the floor's.
                geom.priority = 1
                geom.friction[0] = min(settings.mu)
                if max(settings.mu) == 0.0:
                    geom.condim = 1
            if not self._collides or self._collides[-1][0] != link_name:
                self._collides.append((link_name, settings.self_collide))

    def _pose(self, key):
        """Return (position, quaternion) of the origin at key (take_origins()); none is zero."""
        pose = self._origins.get(key)
        if pose is None:
            return np.zeros(3), np.array(frames.IDENTITY_QUATERNION)
        return pose

    def _gazebo_colour(self, material, link_name):
        """Return the colour a <gazebo> material gives a link's visuals, or None."""
        if material is None:
            return None
        colour = gazebo_colour(material)
        if colour is None:
            self.notes.append(f"link '{link_name}' material '{material}' is not one of "
                              "Gazebo's flat colours; the URDF colour is kept")
        return colour

    def _contact_solref(self, settings):
        """
        Return the MuJoCo solref of a link's contacts: the world's, or from <kp> and <kd>.

        Gazebo's kp is a stiffness in N/m; MuJoCo's contact is a mass-spring-damper with a
        time constant. Taken against the whole robot's mass, 2 pi sqrt(mass / kp) gives the
        robot resting on that link the sinking it has in Gazebo, weight / kp. The damping
        ratio from kd is at least 1, as ODE's implicit step damps a contact at least that
        much. The time constant is at least two timesteps, below which MuJoCo's contacts are
        unstable.
        """
        if settings.kp is None:
            return [CONTACT_TIME_CONSTANT, 1.0]
        time_constant = max(2.0 * math.pi * math.sqrt(self._robot_mass / settings.kp),
                            2.0 * self._timestep)
        damping_ratio = 1.0
        if settings.kd is not None:
            critical = 2.0 * math.sqrt(settings.kp * self._robot_mass)
            damping_ratio = max(1.0, settings.kd / critical)
        return [time_constant, damping_ratio]

    def _keep_links_apart(self):
        """Keep the robot's links from colliding with each other, as Gazebo does."""
        keep_links_apart(self._spec, self._collides, self._weld, self._weld_parent)

    def _set_inertia(self, body, link):
        inertial = link.inertial
        body.explicitinertial = True
        if inertial is None or inertial.mass is None:
            body.mass = 0.0
            body.inertia = [0.0, 0.0, 0.0]
            return
        mass = float(inertial.mass)
        if not math.isfinite(mass) or mass <= 0.0:
            raise UrdfError(f"link '{link.name}' mass must be positive: {mass}")
        position, orientation = self._pose(('inertial', link.name))
        tensor = np.asarray(inertial.inertia if inertial.inertia is not None else np.eye(3),
                            dtype=float)
        if not _finite(tensor):
            raise UrdfError(f"link '{link.name}' inertia contains NaN or infinity")
        # Robots repeat their wheels and legs: each inertia is diagonalised once per robot.
        key = (orientation.tobytes(), tensor.tobytes())
        if key not in self._principal_inertias:
            self._principal_inertias[key] = frames.principal_inertia(orientation, tensor)
        moments, principal = self._principal_inertias[key]
        if not moments[-1] > 0.0:
            raise UrdfError(f"link '{link.name}' inertia is not positive definite "
                            f'(principal moments {moments.tolist()})')
        body.mass = mass
        body.ipos = position
        body.iquat = principal
        body.inertia = moments

    def _add_geom(self, body, geometry, origin, link_name, collision=False):
        """Add a link's geometry to its body; return the geom, or None if it is left out."""
        what = f"link '{link_name}'"
        position, orientation = self._pose(origin)
        mesh_name = None
        if geometry.mesh is not None:
            mesh_name = self.meshes.add(geometry.mesh, what, collision=collision)
            if mesh_name is None:
                return None
        geom = body.add_geom()
        geom.pos, geom.quat = position, orientation
        if geometry.box is not None:
            size = np.asarray(geometry.box.size, dtype=float)
            check_size(size, 3, f'{what} box size', across=(1.0, 1.0, 1.0))
            geom.type = mujoco.mjtGeom.mjGEOM_BOX
            geom.size = size / 2.0
        elif geometry.cylinder is not None:
            size = np.array([geometry.cylinder.radius, geometry.cylinder.length], float)
            check_size(size, 2, f'{what} cylinder radius and length', across=(2.0, 1.0))
            geom.type = mujoco.mjtGeom.mjGEOM_CYLINDER
            geom.size = [size[0], size[1] / 2.0, 0.0]
        elif geometry.sphere is not None:
            size = np.array([geometry.sphere.radius], float)
            check_size(size, 1, f'{what} sphere radius', across=(2.0,))
            geom.type = mujoco.mjtGeom.mjGEOM_SPHERE
            geom.size = [size[0], 0.0, 0.0]
        elif mesh_name is not None:
            geom.type = mujoco.mjtGeom.mjGEOM_MESH
            geom.meshname = mesh_name
        else:
            raise UrdfError(f'{what} has a <geometry> without shape')
        return geom

    def _visual_rgba(self, visual, link_name):
        material = visual.material
        color = None
        if material is not None:
            color = material.color
            if color is None and material.name in self._materials:
                color = self._materials[material.name].color
        if color is None:
            return DEFAULT_VISUAL_RGBA
        # Four Python floats, clipped as np.clip does (-0.0 stays): numpy's calls cost more
        # than these checks, made for every visual.
        rgba = color.rgba.tolist()
        if len(rgba) != 4 or not all(math.isfinite(value) for value in rgba):
            raise UrdfError(f"link '{link_name}' material colour must be four finite numbers")
        return [min(max(value, 0.0), 1.0) for value in rgba]
