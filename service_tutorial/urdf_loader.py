"""
Turn URDF text into a MuJoCo MjSpec, reading the Gazebo extension blocks on the way.

The XML is parsed with a hardened parser before yourdfpy sees it: documents with a DOCTYPE
are refused, so external entities and entity-expansion bombs never reach a parser that would
resolve them. Mesh files are only read from below the model's own folder or a package share.
"""

import dataclasses
from dataclasses import dataclass
import io
import logging
import math
import os

from lxml import etree
import mujoco
import numpy as np
from service_tutorial.diff_drive import DiffDriveConfig
from service_tutorial.diff_drive import ODOMETRY_SOURCE_ENCODER
from service_tutorial.diff_drive import ODOMETRY_SOURCE_WORLD
import yourdfpy

_logger = logging.getLogger('service_tutorial.urdf_loader')

MAX_MODEL_XML_BYTES = 10 * 1024 * 1024
MESH_EXTENSIONS = ('.stl', '.obj')
WORLD_LINK = 'world'
VISUAL_GROUP = 1
COLLISION_GROUP = 3
DEFAULT_VISUAL_RGBA = (0.7, 0.7, 0.7, 1.0)
COLLISION_RGBA = (0.5, 0.2, 0.2, 0.5)
# Contact stiffness as a time constant (s). Stiffer than MuJoCo's 0.02 so that a wheel sinks
# only hundredths of a millimetre into the floor and rolls with its true radius.
CONTACT_TIME_CONSTANT = 0.005
JOINT_TYPES = ('fixed', 'revolute', 'continuous', 'prismatic', 'floating', 'planar')
DIFF_DRIVE_PLUGIN = 'gazebo_ros_diff_drive'
XACRO_NAMESPACE = 'http://www.ros.org/wiki/xacro'


class UrdfError(ValueError):
    """A URDF the loader refuses; the message names the cause and the offending value."""


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
    diff_drive: DiffDriveConfig = None
    mesh_files: tuple = ()


def drive_actuator_name(joint_name):
    """Return the name of the wheel actuator the loader puts on a diff-drive joint."""
    return joint_name + '_drive'


def parse_model_xml(model_xml):
    """Parse model_xml with a hardened parser and return the <robot> root element."""
    data = model_xml.encode('utf-8') if isinstance(model_xml, str) else bytes(model_xml)
    if len(data) > MAX_MODEL_XML_BYTES:
        raise UrdfError(
            f'model_xml is {len(data)} bytes, more than the limit of {MAX_MODEL_XML_BYTES}')
    if not data.strip():
        raise UrdfError('model_xml is empty')
    if b'\x00' in data:
        # UTF-16 or UTF-32 text would slip past the byte scan for a DOCTYPE below.
        raise UrdfError('model_xml must be UTF-8 text')
    # A DTD is the only way to declare entities; refusing it outright means nothing is
    # ever fetched or expanded, whatever the parser would have done.
    if b'<!DOCTYPE' in data or b'<!ENTITY' in data:
        raise UrdfError('model_xml contains a DOCTYPE or ENTITY declaration, which is refused')
    parser = etree.XMLParser(
        resolve_entities=False, no_network=True, load_dtd=False, dtd_validation=False,
        huge_tree=False, remove_comments=True, remove_pis=True)
    try:
        root = etree.fromstring(data, parser)
    except (etree.XMLSyntaxError, ValueError) as error:
        raise UrdfError(f'model_xml does not parse as XML: {error}') from None
    if root.getroottree().docinfo.doctype:
        raise UrdfError('model_xml contains a DOCTYPE declaration, which is refused')
    tag = etree.QName(root).localname
    if tag != 'robot' or etree.QName(root).namespace:
        raise UrdfError(f'model_xml is not URDF: root element is <{tag}>')
    for element in root.iter():
        if isinstance(element.tag, str) and etree.QName(element).namespace == XACRO_NAMESPACE:
            raise UrdfError('model_xml contains xacro macros; run xacro on it first')
    return root


def load_urdf(model_xml, *, base_dir=None, package_resolver=None, timestep=0.002):
    """
    Build a RobotDescription from URDF text, or raise UrdfError naming the problem.

    timestep is the physics timestep of the world the robot goes to; the wheel servos of a
    diff drive are tuned for it.
    """
    root = parse_model_xml(model_xml)
    _check_structure(root)
    for element in list(root.iter()):
        # yourdfpy needs plain tags; namespaced extension elements play no part here.
        if isinstance(element.tag, str) and etree.QName(element).namespace:
            element.getparent().remove(element)
    try:
        urdf = yourdfpy.URDF.load(
            io.BytesIO(etree.tostring(root)), build_scene_graph=False,
            build_collision_scene_graph=False, load_meshes=False,
            load_collision_meshes=False)
    except Exception as error:
        raise UrdfError(f'model_xml is not valid URDF: {error}') from None
    if not urdf.validate():
        raise UrdfError(f'model_xml is not valid URDF: {urdf.errors[0].msg}')
    builder = _SpecBuilder(urdf.robot, base_dir, package_resolver, _read_link_friction(root))
    description = builder.build()
    drive = _read_diff_drive(root, urdf.robot)
    if drive is None:
        return description
    _add_wheel_actuators(description.spec, drive, timestep)
    return dataclasses.replace(description, diff_drive=drive)


def resolve_mesh_path(filename, base_dir, package_resolver):
    """Return the real path of a mesh file, refusing anything outside the allowed roots."""
    if not filename:
        raise UrdfError('a <mesh> has no filename')
    allowed_roots = []
    if filename.startswith('package://'):
        package, _, relative = filename[len('package://'):].partition('/')
        if not package or not relative:
            raise UrdfError(f"mesh '{filename}' is not of the form package://<package>/<path>")
        share = _package_share(package, filename, package_resolver)
        candidate = os.path.join(share, relative)
        allowed_roots.append(share)
    elif filename.startswith('file://') or os.path.isabs(filename):
        candidate = filename[len('file://'):] if filename.startswith('file://') else filename
        if not os.path.isabs(candidate):
            raise UrdfError(f"mesh '{filename}' is a file:// URI without an absolute path")
        if base_dir is not None:
            allowed_roots.append(base_dir)
        share = _share_holding(candidate, package_resolver)
        if share is not None:
            allowed_roots.append(share)
    elif '://' in filename:
        raise UrdfError(f"mesh '{filename}' uses an unsupported URI scheme")
    else:
        if base_dir is None:
            raise UrdfError(f"mesh '{filename}' is a relative path but no base directory is set")
        candidate = os.path.join(base_dir, filename)
        allowed_roots.append(base_dir)
    real_path = os.path.realpath(candidate)
    if not any(_is_within(real_path, root) for root in allowed_roots):
        raise UrdfError(
            f"mesh '{filename}' lies outside the model's folder and package shares")
    extension = os.path.splitext(real_path)[1].lower()
    if extension == '.dae':
        raise UrdfError(
            f"mesh '{filename}' is COLLADA (.dae), which MuJoCo does not read; "
            'convert it to .stl or .obj')
    if extension not in MESH_EXTENSIONS:
        raise UrdfError(
            f"mesh '{filename}' has an unsupported format; use one of "
            f"{', '.join(MESH_EXTENSIONS)}")
    if not os.path.isfile(real_path):
        raise UrdfError(f"mesh '{filename}' does not exist")
    return real_path


def _package_share(package, filename, package_resolver):
    if package_resolver is None:
        raise UrdfError(f"mesh '{filename}' needs a package resolver, and none is available")
    try:
        share = package_resolver(package)
    except Exception:
        share = None
    if not share or not os.path.isdir(share):
        raise UrdfError(f"mesh '{filename}' names package '{package}', which is not found")
    return os.path.realpath(share)


def _share_holding(path, package_resolver):
    """Return the share directory of the package whose files hold path, if there is one."""
    if package_resolver is None:
        return None
    parts = os.path.normpath(path).split(os.sep)
    for index in range(len(parts) - 1):
        if parts[index] != 'share':
            continue
        try:
            share = package_resolver(parts[index + 1])
        except Exception:
            continue
        if share and os.path.realpath(share) == os.path.realpath(
                os.sep.join(parts[:index + 2])):
            return os.path.realpath(share)
    return None


def _is_within(path, root):
    root = os.path.realpath(root)
    return path == root or path.startswith(root.rstrip(os.sep) + os.sep)


def _check_structure(root):
    """Refuse the structural faults yourdfpy would report with a bare KeyError."""
    if not root.get('name'):
        raise UrdfError('model_xml is not valid URDF: <robot> has no name attribute')
    links = root.findall('link')
    if not links:
        raise UrdfError('model_xml has no <link>')
    link_names = set()
    for link in links:
        name = link.get('name')
        if not name:
            raise UrdfError('a <link> has no name attribute')
        if name in link_names:
            raise UrdfError(f"link '{name}' is defined twice")
        link_names.add(name)
    joint_names = set()
    for joint in root.findall('joint'):
        name = joint.get('name')
        if not name:
            raise UrdfError('a <joint> has no name attribute')
        if name in joint_names:
            raise UrdfError(f"joint '{name}' is defined twice")
        joint_names.add(name)
        for end in ('parent', 'child'):
            element = joint.find(end)
            if element is None or not element.get('link'):
                raise UrdfError(f"joint '{name}' has no <{end} link=...>")
        kind = joint.get('type')
        if not kind:
            raise UrdfError(f"joint '{name}' has no type attribute")
        if kind not in JOINT_TYPES:
            raise UrdfError(f"joint '{name}' has unknown type '{kind}'")
        _check_numbers(joint, f"joint '{name}'")
    for link in links:
        _check_numbers(link, f"link '{link.get('name')}'")
        for geometry in link.iter('geometry'):
            if len(geometry) == 0:
                raise UrdfError(f"link '{link.get('name')}' has an empty <geometry>")


# Attributes that hold numbers, by element, and how many numbers each may hold.
_NUMERIC_ATTRIBUTES = {
    'origin': {'xyz': (3,), 'rpy': (3,)}, 'axis': {'xyz': (3,)},
    'dynamics': {'damping': (1,), 'friction': (1,)},
    'limit': {'lower': (1,), 'upper': (1,), 'effort': (1,), 'velocity': (1,)},
    'mass': {'value': (1,)},
    'inertia': {key: (1,) for key in ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')},
    'box': {'size': (3,)}, 'cylinder': {'radius': (1,), 'length': (1,)},
    'sphere': {'radius': (1,)}, 'mesh': {'scale': (1, 3)}, 'color': {'rgba': (4,)}}


def _check_numbers(element, what):
    for child in element.iter(*_NUMERIC_ATTRIBUTES):
        for key, counts in _NUMERIC_ATTRIBUTES[child.tag].items():
            text = child.get(key)
            if text is None:
                continue
            where = f'{what} <{child.tag} {key}>'
            values = _parse_numbers(text, where)
            if len(values) not in counts:
                expected = ' or '.join(str(count) for count in counts)
                raise UrdfError(f'{where} must hold {expected} numbers, not {len(values)}: '
                                f'{_quoted(text)}')


def _quoted(text, limit=80):
    """Return a piece of the model's text in quotes for a message, cut short if long."""
    return f"'{text[:limit]}...'" if len(text) > limit else f"'{text}'"


def _parse_numbers(text, what):
    try:
        values = [float(token) for token in text.replace(',', ' ').split()]
    except ValueError:
        raise UrdfError(f'{what} is not a number: {_quoted(text)}') from None
    if not all(math.isfinite(value) for value in values):
        raise UrdfError(f'{what} contains NaN or infinity: {_quoted(text)}')
    return values


def _read_link_friction(root):
    """Return {link: (mu1, mu2)} from <gazebo reference="link"> blocks."""
    friction = {}
    link_names = {link.get('name') for link in root.findall('link')}
    for block in root.findall('gazebo'):
        reference = block.get('reference')
        if reference is None or reference not in link_names:
            continue
        values = {}
        for key in ('mu1', 'mu2'):
            element = block.find(key)
            if element is None:
                continue
            text = element.get('value') if element.get('value') is not None else element.text
            value = _parse_numbers(text or '', f"gazebo <{key}> of link '{reference}'")
            if len(value) != 1 or value[0] < 0.0:
                raise UrdfError(
                    f"gazebo <{key}> of link '{reference}' must be one number >= 0: '{text}'")
            values[key] = value[0]
        if values:
            mu1 = values.get('mu1', values.get('mu2'))
            mu2 = values.get('mu2', mu1)
            friction[reference] = (mu1, mu2)
    return friction


# ROS 2 parameter name -> ROS 1 parameter name of gazebo_ros_diff_drive.
_ROS1_NAMES = {
    'left_joint': 'leftJoint',
    'right_joint': 'rightJoint',
    'wheel_separation': 'wheelSeparation',
    'wheel_diameter': 'wheelDiameter',
    'max_wheel_torque': 'wheelTorque',
    'max_wheel_acceleration': 'wheelAcceleration',
    'odometry_frame': 'odometryFrame',
    'robot_base_frame': 'robotBaseFrame',
    'odometry_source': 'odometrySource',
    'command_topic': 'commandTopic',
    'odometry_topic': 'odometryTopic',
    'publish_odom_tf': 'publishOdomTF',
    'publish_wheel_tf': 'publishWheelTF',
    'update_rate': 'updateRate',
}


def _read_diff_drive(root, robot):
    """Return the DiffDriveConfig of the robot's diff-drive plugin, or None."""
    plugins = [plugin for block in root.findall('gazebo') if block.get('reference') is None
               for plugin in block.findall('plugin')
               if DIFF_DRIVE_PLUGIN in (plugin.get('filename') or '')]
    if not plugins:
        return None
    if len(plugins) > 1:
        raise UrdfError('model_xml carries more than one diff-drive plugin')
    plugin = plugins[0]
    ros1 = plugin.find('leftJoint') is not None or plugin.find('rightJoint') is not None

    def texts(key):
        tag = _ROS1_NAMES.get(key, key) if ros1 else key
        return [(element.text or '').strip() for element in plugin.findall(tag)]

    def text(key, default):
        values = texts(key)
        return values[-1] if values else default

    def number(key, default, minimum, inclusive):
        value_text = text(key, None)
        if value_text is None:
            return default
        value = _parse_numbers(value_text, f'diff-drive <{key}>')
        if len(value) != 1 or value[0] < minimum or (value[0] == minimum and not inclusive):
            bound = '>=' if inclusive else '>'
            raise UrdfError(f'diff-drive <{key}> must be one number {bound} {minimum}: '
                            f"'{value_text}'")
        return value[0]

    def flag(key, default):
        value_text = text(key, None)
        if value_text is None:
            return default
        if value_text.lower() not in ('true', 'false', '1', '0'):
            raise UrdfError(f"diff-drive <{key}> must be true or false: '{value_text}'")
        return value_text.lower() in ('true', '1')

    left_joints = tuple(texts('left_joint'))
    right_joints = tuple(texts('right_joint'))
    if not left_joints or not right_joints or len(left_joints) != len(right_joints):
        raise UrdfError('diff-drive plugin needs as many <left_joint> as <right_joint>')
    joints = {joint.name: joint for joint in robot.joints}
    for name in left_joints + right_joints:
        if name not in joints:
            raise UrdfError(f"diff-drive wheel joint '{name}' is not a joint of the robot")
        if joints[name].type not in ('continuous', 'revolute'):
            raise UrdfError(f"diff-drive wheel joint '{name}' is {joints[name].type}, "
                            'not continuous or revolute')
    if len(set(left_joints + right_joints)) != 2 * len(left_joints):
        raise UrdfError('diff-drive plugin names the same wheel joint twice')

    source_text = text('odometry_source', '1').lower()
    sources = {'0': ODOMETRY_SOURCE_ENCODER, 'encoder': ODOMETRY_SOURCE_ENCODER,
               '1': ODOMETRY_SOURCE_WORLD, 'world': ODOMETRY_SOURCE_WORLD}
    if source_text not in sources:
        raise UrdfError(
            f"diff-drive <odometry_source> must be 0 (encoder) or 1 (world): '{source_text}'")

    legacy_mode = False
    if ros1:
        # gazebo_ros (ROS 1) swapped the wheels unless told <legacyMode>false</legacyMode>.
        legacy_text = plugin.findtext('legacyMode')
        if legacy_text is None:
            _logger.warning('ROS 1 diff-drive plugin has no <legacyMode>; like gazebo_ros it '
                            'defaults to true and swaps the wheels. Add '
                            '<legacyMode>false</legacyMode> unless the robot relies on that.')
        legacy_mode = (legacy_text or 'true').strip().lower() in ('true', '1')
        if legacy_mode:
            left_joints, right_joints = right_joints, left_joints

    ros = plugin.find('ros')
    namespace = ''
    remappings = ()
    if ros is not None:
        namespace = (ros.findtext('namespace') or '').strip()
        remappings = tuple((element.text or '').strip() for element in ros.findall('remapping'))
    namespace = namespace or (plugin.findtext('robotNamespace') or '').strip()

    return DiffDriveConfig(
        left_joints=left_joints,
        right_joints=right_joints,
        wheel_separation=number('wheel_separation', 0.34, 0.0, False),
        wheel_diameter=number('wheel_diameter', 0.15, 0.0, False),
        max_wheel_torque=number('max_wheel_torque', 5.0, 0.0, False),
        max_wheel_acceleration=number('max_wheel_acceleration', 0.0, 0.0, True),
        odometry_frame=text('odometry_frame', 'odom'),
        robot_base_frame=text('robot_base_frame', 'base_footprint'),
        odometry_source=sources[source_text],
        command_topic=text('command_topic', 'cmd_vel'),
        odometry_topic=text('odometry_topic', 'odom'),
        publish_odom=flag('publish_odom', True),
        publish_odom_tf=flag('publish_odom_tf', True),
        publish_wheel_tf=flag('publish_wheel_tf', False),
        update_rate=number('update_rate', 100.0, 0.0, True),
        ros_namespace=namespace,
        ros_remappings=remappings,
        legacy_mode=legacy_mode)


def _add_wheel_actuators(spec, drive, timestep):
    """
    Put a torque-limited velocity servo on every wheel joint.

    The servo's activation is the wheel speed set point and its control input is the rate of
    change of that set point, which lets the world ramp speeds at max_wheel_acceleration
    without touching the controls every physics step.

    MuJoCo treats the servo's damping implicitly only while the torque is below its limit.
    With gain kv = joint inertia / timestep, a torque-limited step can never carry the wheel
    past its set point, so the servo neither chatters nor goes unstable. Each wheel gets an
    armature (motor rotor inertia seen through the gearbox) equal to its share of the robot's
    mass seen at the rim, the usual inertia-matched motor sizing; that raises the gain until
    the wheel follows its set point within a few milliseconds, like a Gazebo joint motor.
    """
    robot_mass = sum(body.mass for body in spec.bodies)
    wheel_joints = drive.left_joints + drive.right_joints
    armature = robot_mass * drive.wheel_radius ** 2 / len(wheel_joints)
    for joint_name in wheel_joints:
        joint = spec.joint(joint_name)
        joint.armature = armature
        kv = (_inertia_about_axis(joint.parent, joint.axis) + armature) / timestep
        actuator = spec.add_actuator(name=drive_actuator_name(joint_name), target=joint_name)
        actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
        actuator.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.gainprm[0] = kv
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.biasprm[:3] = [0.0, 0.0, -kv]
        actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.forcerange = [-drive.max_wheel_torque, drive.max_wheel_torque]
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        actuator.actlimited = mujoco.mjtLimited.mjLIMITED_FALSE


def _inertia_about_axis(body, axis):
    """Return the moment of inertia of a body about a unit axis through its origin."""
    axis = np.asarray(axis, dtype=float)
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, np.asarray(body.iquat, dtype=float))
    rotation = rotation.reshape(3, 3)
    tensor = rotation @ np.diag(np.asarray(body.inertia, dtype=float)) @ rotation.T
    offset = np.asarray(body.ipos, dtype=float)
    return float(axis @ tensor @ axis + body.mass * (offset @ offset - (offset @ axis) ** 2))


def _pose(matrix, what):
    """Return (position, quaternion) of a 4x4 homogeneous transform."""
    if matrix is None:
        return np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0])
    matrix = np.asarray(matrix, dtype=float)
    if not np.all(np.isfinite(matrix)):
        raise UrdfError(f'{what} origin contains NaN or infinity')
    quaternion = np.zeros(4)
    mujoco.mju_mat2Quat(quaternion, np.ascontiguousarray(matrix[:3, :3]).ravel())
    return matrix[:3, 3].copy(), quaternion


class _SpecBuilder:
    """Walks a yourdfpy robot from its root link and adds MuJoCo bodies for every link."""

    def __init__(self, robot, base_dir, package_resolver, friction):
        self._robot = robot
        self._base_dir = os.path.realpath(base_dir) if base_dir else None
        self._package_resolver = package_resolver
        self._friction = friction
        self._links = {link.name: link for link in robot.links}
        self._materials = {material.name: material for material in robot.materials
                           if material.name}
        self._mesh_files = []
        self._spec = mujoco.MjSpec()
        self._spec.compiler.degree = False
        self._spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
        self._spec.strippath = False

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
        root_body = self._spec.worldbody.add_body(name=root)
        if world_joints:
            world_joint = world_joints[0]
            position, orientation = _pose(world_joint.origin, f"joint '{world_joint.name}'")
            root_position, root_orientation = tuple(position), tuple(orientation)
            anchored = True
            if world_joint.type != 'fixed':
                self._add_joint(root_body, world_joint)
        else:
            root_body.add_freejoint()
        self._fill_link(root_body, root)

        visited = {root}
        joint_names = [joint.name for joint in world_joints if joint.type != 'fixed']
        stack = [(root_body, joint) for joint in reversed(children.get(root, []))]
        while stack:
            parent_body, joint = stack.pop()
            if joint.child in visited:
                raise UrdfError(f"joints form a loop at link '{joint.child}'")
            visited.add(joint.child)
            position, orientation = _pose(joint.origin, f"joint '{joint.name}'")
            body = parent_body.add_body(name=joint.child, pos=position, quat=orientation)
            if joint.type != 'fixed':
                self._add_joint(body, joint)
                joint_names.append(joint.name)
            self._fill_link(body, joint.child)
            stack.extend((body, child) for child in reversed(children.get(joint.child, [])))
        unreached = [name for name in self._links if name not in visited and name != WORLD_LINK]
        if unreached:
            raise UrdfError(f"joints form a loop: links {', '.join(unreached)} are not "
                            f"reached from root link '{root}'")
        links = tuple(name for name in self._links if name != WORLD_LINK)
        return RobotDescription(
            robot_name=robot.name, spec=self._spec, root_link=root, anchored=anchored,
            root_position=root_position, root_orientation=root_orientation, links=links,
            joints=tuple(joint_names), mesh_files=tuple(self._mesh_files))

    def _add_joint(self, body, joint):
        axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)):
            raise UrdfError(f"joint '{joint.name}' axis is not three finite numbers")
        norm = np.linalg.norm(axis)
        if norm < 1e-9:
            raise UrdfError(f"joint '{joint.name}' axis is zero")
        kind = (mujoco.mjtJoint.mjJNT_SLIDE if joint.type == 'prismatic'
                else mujoco.mjtJoint.mjJNT_HINGE)
        mj_joint = body.add_joint(name=joint.name, type=kind, axis=axis / norm)
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
                value = _parse_numbers(str(text), f"joint '{joint.name}' {attribute}")
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
        self._set_inertia(body, link)
        for visual in link.visuals:
            geom = self._add_geom(body, visual.geometry, visual.origin, link_name)
            if geom.type == mujoco.mjtGeom.mjGEOM_MESH:
                # Visual meshes are often open surfaces; they carry no mass here anyway.
                self._spec.mesh(geom.meshname).inertia = mujoco.mjtMeshInertia.mjMESH_INERTIA_SHELL
            geom.contype = 0
            geom.conaffinity = 0
            geom.group = VISUAL_GROUP
            geom.rgba = self._visual_rgba(visual, link_name)
        mu = self._friction.get(link_name)
        for collision in link.collisions:
            geom = self._add_geom(body, collision.geometry, collision.origin, link_name)
            geom.group = COLLISION_GROUP
            geom.rgba = COLLISION_RGBA
            geom.solref = [CONTACT_TIME_CONSTANT, 1.0]
            if mu is not None:
                # ODE combines the friction of two surfaces with min(); MuJoCo takes the
                # higher-priority geom's, so the link's own setting wins over the floor's.
                geom.priority = 1
                geom.friction[0] = min(mu)
                if max(mu) == 0.0:
                    geom.condim = 1

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
        position, orientation = _pose(inertial.origin, f"link '{link.name}' inertial")
        tensor = np.asarray(inertial.inertia if inertial.inertia is not None else np.eye(3),
                            dtype=float)
        if not np.all(np.isfinite(tensor)):
            raise UrdfError(f"link '{link.name}' inertia contains NaN or infinity")
        rotation = np.zeros(9)
        mujoco.mju_quat2Mat(rotation, orientation)
        rotation = rotation.reshape(3, 3)
        tensor = rotation @ tensor @ rotation.T
        moments, axes = np.linalg.eigh(tensor)
        if moments[0] <= 0.0:
            raise UrdfError(f"link '{link.name}' inertia is not positive definite "
                            f'(principal moments {moments.tolist()})')
        if np.linalg.det(axes) < 0.0:
            axes[:, 2] = -axes[:, 2]
        principal = np.zeros(4)
        mujoco.mju_mat2Quat(principal, np.ascontiguousarray(axes).ravel())
        body.mass = mass
        body.ipos = position
        body.iquat = principal
        body.inertia = moments

    def _add_geom(self, body, geometry, origin, link_name):
        what = f"link '{link_name}'"
        position, orientation = _pose(origin, f'{what} geometry')
        geom = body.add_geom(pos=position, quat=orientation)
        if geometry.box is not None:
            size = np.asarray(geometry.box.size, dtype=float)
            self._check_size(size, 3, f'{what} box size')
            geom.type = mujoco.mjtGeom.mjGEOM_BOX
            geom.size = size / 2.0
        elif geometry.cylinder is not None:
            size = np.array([geometry.cylinder.radius, geometry.cylinder.length], float)
            self._check_size(size, 2, f'{what} cylinder radius and length')
            geom.type = mujoco.mjtGeom.mjGEOM_CYLINDER
            geom.size = [size[0], size[1] / 2.0, 0.0]
        elif geometry.sphere is not None:
            size = np.array([geometry.sphere.radius], float)
            self._check_size(size, 1, f'{what} sphere radius')
            geom.type = mujoco.mjtGeom.mjGEOM_SPHERE
            geom.size = [size[0], 0.0, 0.0]
        elif geometry.mesh is not None:
            path = resolve_mesh_path(geometry.mesh.filename, self._base_dir,
                                     self._package_resolver)
            scale = geometry.mesh.scale if geometry.mesh.scale is not None else 1.0
            scale = np.broadcast_to(np.asarray(scale, dtype=float), (3,)).copy()
            if not np.all(np.isfinite(scale)) or np.any(scale == 0.0):
                raise UrdfError(f'{what} mesh scale must be finite and non-zero')
            mesh = self._spec.add_mesh(name=f'mesh{len(self._mesh_files)}', file=path)
            mesh.scale = scale
            self._mesh_files.append(path)
            geom.type = mujoco.mjtGeom.mjGEOM_MESH
            geom.meshname = mesh.name
        else:
            raise UrdfError(f'{what} has a <geometry> without shape')
        return geom

    @staticmethod
    def _check_size(size, count, what):
        if size.shape != (count,) or not np.all(np.isfinite(size)) or np.any(size <= 0.0):
            raise UrdfError(f'{what} must be {count} positive numbers: {size.tolist()}')

    def _visual_rgba(self, visual, link_name):
        material = visual.material
        color = None
        if material is not None:
            color = material.color
            if color is None and material.name in self._materials:
                color = self._materials[material.name].color
        if color is None:
            return DEFAULT_VISUAL_RGBA
        rgba = np.asarray(color.rgba, dtype=float)
        if rgba.shape != (4,) or not np.all(np.isfinite(rgba)):
            raise UrdfError(f"link '{link_name}' material colour must be four finite numbers")
        return np.clip(rgba, 0.0, 1.0)
