"""
The Gazebo diff-drive plugin (gazebo_ros_diff_drive), simulation side.

Its parameters, the wheel servos it puts on a robot, the kinematics, encoder odometry, and
DiffDrive, the controller the world's step drives. Topic names are the ROS face's business:
they stay in the plugin's raw block, readable with parameter().
"""

from dataclasses import dataclass
import logging
import math

import mujoco
import numpy as np
from service_tutorial.sim import frames
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.urdf.hardened_xml import parse_numbers
from service_tutorial.sim.urdf.hardened_xml import UrdfError

_logger = logging.getLogger(__name__)

ODOMETRY_SOURCE_ENCODER = 0
ODOMETRY_SOURCE_WORLD = 1
# Fastest a diff drive turns a wheel's rim, in m/s; faster commands are scaled down to it.
MAX_WHEEL_RIM_SPEED = 10.0


@dataclass(frozen=True)
class DiffDriveConfig:
    """
    Settings of a gazebo_ros diff-drive plugin, in ROS 2 names and SI units.

    Wheel joints are given in pairs; every left joint turns at the left wheel speed.
    ROS 1 legacy mode is resolved while parsing by swapping the two joint lists.
    """

    left_joints: tuple
    right_joints: tuple
    wheel_separation: float = 0.34
    wheel_diameter: float = 0.15
    max_wheel_torque: float = 5.0
    max_wheel_acceleration: float = 0.0  # m/s^2 at the wheel rim; 0 means unlimited
    odometry_frame: str = 'odom'
    robot_base_frame: str = 'base_footprint'
    odometry_source: int = ODOMETRY_SOURCE_WORLD
    publish_odom: bool = True
    publish_odom_tf: bool = True
    publish_wheel_tf: bool = False
    update_rate: float = 100.0
    legacy_mode: bool = False

    @property
    def wheel_radius(self):
        """Return the wheel radius in metres."""
        return self.wheel_diameter / 2.0

    @property
    def left_joint(self):
        """Return the first left wheel joint, the one encoder odometry reads."""
        return self.left_joints[0]

    @property
    def right_joint(self):
        """Return the first right wheel joint, the one encoder odometry reads."""
        return self.right_joints[0]


@dataclass(frozen=True, eq=False)
class Odometry:
    """Odometry of a diff-drive robot: pose in the odometry frame, twist in the base frame."""

    position: np.ndarray          # (3,) metres, in odometry_frame
    orientation: np.ndarray       # (4,) unit quaternion (w, x, y, z), in odometry_frame
    linear_velocity: np.ndarray   # (3,) m/s, in robot_base_frame
    angular_velocity: np.ndarray  # (3,) rad/s, in robot_base_frame
    odometry_frame: str
    robot_base_frame: str


def wheel_speeds(linear_x, angular_z, wheel_separation, wheel_radius):
    """Return (left, right) wheel speeds in rad/s for a body twist in m/s and rad/s."""
    rim_offset = angular_z * wheel_separation / 2.0
    return ((linear_x - rim_offset) / wheel_radius, (linear_x + rim_offset) / wheel_radius)


def body_velocity(left_speed, right_speed, wheel_separation, wheel_radius):
    """Return (linear_x, angular_z) of the base for wheel speeds in rad/s."""
    linear_x = wheel_radius * (left_speed + right_speed) / 2.0
    angular_z = wheel_radius * (right_speed - left_speed) / wheel_separation
    return linear_x, angular_z


def integrate_arc(x, y, yaw, distance, turn):
    """Advance a planar pose along a circular arc of given length and heading change."""
    if abs(turn) < 1e-9:
        # Second-order midpoint step; exact in the limit of a straight line.
        heading = yaw + turn / 2.0
        return x + distance * math.cos(heading), y + distance * math.sin(heading), yaw + turn
    radius = distance / turn
    new_yaw = yaw + turn
    return (x + radius * (math.sin(new_yaw) - math.sin(yaw)),
            y - radius * (math.cos(new_yaw) - math.cos(yaw)),
            new_yaw)


class EncoderOdometry:
    """Dead reckoning of a planar pose from the angles of the two wheels."""

    def __init__(self, wheel_separation, wheel_radius):
        """Start at the origin with both wheel angles at zero."""
        self.wheel_separation = wheel_separation
        self.wheel_radius = wheel_radius
        self.reset(0.0, 0.0)

    def reset(self, left_angle, right_angle):
        """Put the pose back to the origin and remember the current wheel angles."""
        self.x = 0.0
        self.y = 0.0
        self.yaw = 0.0
        self._left_angle = left_angle
        self._right_angle = right_angle

    def update(self, left_angle, right_angle):
        """Integrate the wheel rotation since the last update as one arc."""
        left_travel = (left_angle - self._left_angle) * self.wheel_radius
        right_travel = (right_angle - self._right_angle) * self.wheel_radius
        self._left_angle = left_angle
        self._right_angle = right_angle
        distance = (left_travel + right_travel) / 2.0
        turn = (right_travel - left_travel) / self.wheel_separation
        self.x, self.y, self.yaw = integrate_arc(self.x, self.y, self.yaw, distance, turn)


def drive_actuator_name(joint_name):
    """Return the name of the wheel actuator the plugin puts on a diff-drive joint."""
    return joint_name + '_drive'


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


def is_ros1_block(block):
    """Return True if a diff-drive block is written with gazebo_ros's ROS 1 parameter names."""
    return 'leftJoint' in block.parameters or 'rightJoint' in block.parameters


def parameter_texts(block, key):
    """Return the texts of a diff-drive parameter, by its ROS 2 name, in either generation."""
    return block.texts(_ROS1_NAMES.get(key, key) if is_ros1_block(block) else key)


def parameter(block, key, default=None):
    """Return the last text given for a diff-drive parameter such as command_topic, or default."""
    values = parameter_texts(block, key)
    return values[-1] if values else default


def _number(block, key, default, minimum, inclusive):
    value_text = parameter(block, key)
    if value_text is None:
        return default
    value = parse_numbers(value_text, f'diff-drive <{key}>')
    if len(value) != 1 or value[0] < minimum or (value[0] == minimum and not inclusive):
        bound = '>=' if inclusive else '>'
        raise UrdfError(f'diff-drive <{key}> must be one number {bound} {minimum}: '
                        f"'{value_text}'")
    return value[0]


def _flag(block, key, default):
    value_text = parameter(block, key)
    if value_text is None:
        return default
    if value_text.lower() not in ('true', 'false', '1', '0'):
        raise UrdfError(f"diff-drive <{key}> must be true or false: '{value_text}'")
    return value_text.lower() in ('true', '1')


def _wheel_joints(block, robot):
    """Return the (left, right) wheel joint names of a block, checked against the robot."""
    left_joints = parameter_texts(block, 'left_joint')
    right_joints = parameter_texts(block, 'right_joint')
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
    return left_joints, right_joints


def read_config(block, robot):
    """Return the DiffDriveConfig of a diff-drive plugin block of a yourdfpy robot."""
    left_joints, right_joints = _wheel_joints(block, robot)
    source_text = parameter(block, 'odometry_source', '1').lower()
    sources = {'0': ODOMETRY_SOURCE_ENCODER, 'encoder': ODOMETRY_SOURCE_ENCODER,
               '1': ODOMETRY_SOURCE_WORLD, 'world': ODOMETRY_SOURCE_WORLD}
    if source_text not in sources:
        raise UrdfError(
            f"diff-drive <odometry_source> must be 0 (encoder) or 1 (world): '{source_text}'")

    legacy_mode = False
    if is_ros1_block(block):
        # gazebo_ros (ROS 1) swapped the wheels unless told <legacyMode>false</legacyMode>.
        legacy_texts = block.parameters.get('legacyMode')
        if not legacy_texts:
            _logger.warning('ROS 1 diff-drive plugin has no <legacyMode>; like gazebo_ros it '
                            'defaults to true and swaps the wheels. Add '
                            '<legacyMode>false</legacyMode> unless the robot relies on that.')
        legacy_mode = ((legacy_texts or ('',))[0] or 'true').strip().lower() in ('true', '1')
        if legacy_mode:
            left_joints, right_joints = right_joints, left_joints

    return DiffDriveConfig(
        left_joints=left_joints,
        right_joints=right_joints,
        wheel_separation=_number(block, 'wheel_separation', 0.34, 0.0, False),
        wheel_diameter=_number(block, 'wheel_diameter', 0.15, 0.0, False),
        max_wheel_torque=_number(block, 'max_wheel_torque', 5.0, 0.0, False),
        max_wheel_acceleration=_number(block, 'max_wheel_acceleration', 0.0, 0.0, True),
        odometry_frame=parameter(block, 'odometry_frame', 'odom'),
        robot_base_frame=parameter(block, 'robot_base_frame', 'base_footprint'),
        odometry_source=sources[source_text],
        publish_odom=_flag(block, 'publish_odom', True),
        publish_odom_tf=_flag(block, 'publish_odom_tf', True),
        publish_wheel_tf=_flag(block, 'publish_wheel_tf', False),
        update_rate=_number(block, 'update_rate', 100.0, 0.0, True),
        legacy_mode=legacy_mode)


def add_wheel_actuators(spec, config, timestep):
    """
    Put a torque-limited velocity servo on every wheel joint.

    The servo's activation is the wheel speed set point and its control input is the rate of
    change of that set point, which lets the drive ramp speeds at max_wheel_acceleration
    without touching the controls every physics step.

    MuJoCo treats the servo's damping implicitly only while the torque is below its limit.
    With gain kv = joint inertia / timestep, a torque-limited step can never carry the wheel
    past its set point, so the servo neither chatters nor goes unstable. Each wheel gets an
    armature (motor rotor inertia seen through the gearbox) equal to its share of the robot's
    mass seen at the rim, the usual inertia-matched motor sizing; that raises the gain until
    the wheel follows its set point within a few milliseconds, like a Gazebo joint motor.
    """
    robot_mass = sum(body.mass for body in spec.bodies)
    wheel_joints = config.left_joints + config.right_joints
    armature = robot_mass * config.wheel_radius ** 2 / len(wheel_joints)
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
        actuator.forcerange = [-config.max_wheel_torque, config.max_wheel_torque]
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        actuator.actlimited = mujoco.mjtLimited.mjLIMITED_FALSE


def _inertia_about_axis(body, axis):
    """Return the moment of inertia of a body about a unit axis through its origin."""
    axis = np.asarray(axis, dtype=float)
    tensor = frames.rotate_tensor(body.iquat, np.diag(np.asarray(body.inertia, dtype=float)))
    offset = np.asarray(body.ipos, dtype=float)
    return float(axis @ tensor @ axis + body.mass * (offset @ offset - (offset @ axis) ** 2))


class DiffDrive(Plugin):
    """
    A robot's diff drive at run time: wheel set points, command timeout, odometry.

    Wheel speeds are servo set points held in the actuators' activations; a ramp at the
    acceleration limit runs in MuJoCo by itself, and the drive only acts at its events: a
    ramp's end and the lapse of a command.
    """

    title = 'diff-drive'

    def __init__(self, config, block):
        """Start at rest, with no command and odometry at the origin."""
        super().__init__(config, block)
        wheel_count = len(config.left_joints) + len(config.right_joints)
        self.acceleration = config.max_wheel_acceleration / config.wheel_radius  # rad/s^2
        self.targets = np.zeros(wheel_count)
        self.ramp_end = np.full(wheel_count, math.inf)
        self.expiry = math.inf
        self.commanded_at = None  # simulation time of the command in force, if there is one
        self.encoder = EncoderOdometry(config.wheel_separation, config.wheel_radius)
        self.origin_position = np.zeros(3)
        self.origin_orientation = np.array(frames.IDENTITY_QUATERNION)

    @classmethod
    def configure(cls, block, robot):
        """Return the DiffDriveConfig of a diff-drive block (see read_config)."""
        return read_config(block, robot)

    @classmethod
    def build(cls, spec, config, timestep):
        """Put the wheel servos on the robot's spec (see add_wheel_actuators)."""
        add_wheel_actuators(spec, config, timestep)

    def bind(self, world, model):
        """Find the wheel actuators, wheel joints and base body in the compiled model."""
        super().bind(world, model)
        mj_model, config = world.model, self.config
        self._actuator_ids = np.array(
            [mj_model.actuator(model.scoped(drive_actuator_name(joint))).id
             for joint in config.left_joints + config.right_joints], dtype=int)
        self._act_adr = mj_model.actuator_actadr[self._actuator_ids].astype(int)
        base_link = config.robot_base_frame
        if base_link not in model.description.links:
            base_link = model.description.root_link
        self._base_body_id = mj_model.body(model.scoped(base_link)).id
        left, right = (mj_model.joint(model.scoped(name))
                       for name in (config.left_joint, config.right_joint))
        self._wheel_qpos_adr = (int(left.qposadr[0]), int(right.qposadr[0]))
        self._wheel_dof_adr = (int(left.dofadr[0]), int(right.dofadr[0]))

    def next_event(self):
        """Return when the next ramp ends or the command lapses."""
        return min(self.expiry, float(self.ramp_end.min()))

    def command(self, linear_x, angular_z, timeout):
        """
        Drive at a body twist until timeout seconds pass (0: forever); return what is done.

        A command that would turn a wheel rim faster than MAX_WHEEL_RIM_SPEED is scaled down
        to that speed, keeping the radius of the turn.
        """
        config = self.config
        # Scale before the wheel speeds are worked out, so that no sum of huge values overflows.
        fastest_rim = max(abs(linear_x), abs(angular_z) * config.wheel_separation / 2.0)
        if fastest_rim > MAX_WHEEL_RIM_SPEED:
            scale = MAX_WHEEL_RIM_SPEED / fastest_rim
            linear_x, angular_z = linear_x * scale, angular_z * scale
        left, right = wheel_speeds(linear_x, angular_z, config.wheel_separation,
                                   config.wheel_radius)
        fastest_wheel = max(abs(left), abs(right)) * config.wheel_radius
        if fastest_wheel > MAX_WHEEL_RIM_SPEED:
            scale = MAX_WHEEL_RIM_SPEED / fastest_wheel
            linear_x, angular_z = linear_x * scale, angular_z * scale
            left, right = left * scale, right * scale
        self._update_encoder()
        self._set_wheel_targets(left, right)
        self.commanded_at = self.world.data.time
        self.set_timeout(timeout)
        return linear_x, angular_z

    def set_timeout(self, timeout):
        """Let the command in force lapse timeout seconds after it came (0: never)."""
        if self.commanded_at is not None:
            self.expiry = self.commanded_at + timeout if timeout > 0.0 else math.inf

    def _set_wheel_targets(self, left, right):
        """
        Set wheel speed set points, ramped at the drive's acceleration limit if it has one.

        The servo's activation is its speed set point and its control is the set point's rate
        of change, so a ramp needs no work between its start and its end.
        """
        data, timestep = self.world.data, self.world.timestep
        half = len(self.targets) // 2
        self.targets[:half] = left
        self.targets[half:] = right
        for index, (actuator, act) in enumerate(zip(self._actuator_ids, self._act_adr)):
            change = self.targets[index] - data.act[act]
            ramp_steps = (math.floor(abs(change) / (self.acceleration * timestep))
                          if self.acceleration > 0.0 else 0)
            if ramp_steps == 0:
                data.act[act] = self.targets[index]
                data.ctrl[actuator] = 0.0
                self.ramp_end[index] = math.inf
            else:
                data.ctrl[actuator] = math.copysign(self.acceleration, change)
                self.ramp_end[index] = data.time + ramp_steps * timestep

    def update(self, now):
        """End the ramps that are due, and stop the wheels if the command lapsed."""
        data = self.world.data
        for index in np.nonzero(self.ramp_end <= now)[0]:
            data.act[self._act_adr[index]] = self.targets[index]
            data.ctrl[self._actuator_ids[index]] = 0.0
            self.ramp_end[index] = math.inf
        if self.expiry <= now:
            self._update_encoder()
            self._set_wheel_targets(0.0, 0.0)
            self.expiry = math.inf
            self.commanded_at = None

    def reset(self):
        """Stop the wheels at once, drop the command and start odometry where the robot is."""
        data = self.world.data
        self.targets[:] = 0.0
        self.ramp_end[:] = math.inf
        self.expiry = math.inf
        self.commanded_at = None
        data.act[self._act_adr] = 0.0
        data.ctrl[self._actuator_ids] = 0.0
        qpos = data.qpos
        self.encoder.reset(*(qpos[address] for address in self._wheel_qpos_adr))
        base = self.world.body_state(self._base_body_id)
        self.origin_position = base.position
        self.origin_orientation = base.orientation

    def _update_encoder(self):
        qpos = self.world.data.qpos
        self.encoder.update(*(qpos[address] for address in self._wheel_qpos_adr))

    def odometry(self):
        """Return the robot's odometry, from its wheel encoders or from ground truth."""
        config = self.config
        if config.odometry_source == ODOMETRY_SOURCE_ENCODER:
            self._update_encoder()
            encoder = self.encoder
            qvel = self.world.data.qvel
            linear_x, angular_z = body_velocity(
                *(qvel[address] for address in self._wheel_dof_adr), config.wheel_separation,
                config.wheel_radius)
            return Odometry(
                position=np.array([encoder.x, encoder.y, 0.0]),
                orientation=frames.yaw_quaternion(encoder.yaw),
                linear_velocity=np.array([linear_x, 0.0, 0.0]),
                angular_velocity=np.array([0.0, 0.0, angular_z]),
                odometry_frame=config.odometry_frame,
                robot_base_frame=config.robot_base_frame)
        base = self.world.body_state(self._base_body_id)
        position, orientation = frames.relative(self.origin_position, self.origin_orientation,
                                                base.position, base.orientation)
        return Odometry(
            position=position, orientation=orientation,
            linear_velocity=frames.rotate_back(base.orientation, base.linear_velocity),
            angular_velocity=frames.rotate_back(base.orientation, base.angular_velocity),
            odometry_frame=config.odometry_frame,
            robot_base_frame=config.robot_base_frame)


PLUGIN = DiffDrive
