"""
The Gazebo diff-drive plugin (gazebo_ros_diff_drive), simulation side.

The wheel servos it puts on a robot, the kinematics, encoder odometry, and DiffDrive, the
controller the world's step drives; drive_config.py reads its parameters in both
generations' spellings. Topic names are the ROS face's business: they stay in the plugin's
raw block, readable with drive_config.parameter().
"""

from dataclasses import dataclass
import math

import mujoco
import numpy as np
from service_tutorial.sim import frames
from service_tutorial.sim import validation
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.plugins.drive_config import ODOMETRY_SOURCE_ENCODER
from service_tutorial.sim.plugins.drive_config import read_diff_drive

# Fastest a drive turns a wheel's rim, in m/s; faster commands are scaled down to it.
MAX_WHEEL_RIM_SPEED = 10.0


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


def wheel_values(array, addresses):
    """
    Return the entries of an MjData array (qpos, qvel) at the wheels' addresses, as floats.

    Python floats (item()): numpy's scalars would make each step of the encoders' arc slower,
    for every robot at every odometry turn.
    """
    return [array.item(address) for address in addresses]


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

    def odometry(self, left_speed, right_speed, odometry_frame, robot_base_frame):
        """Return the pose reckoned so far, with the base's twist at these wheel speeds."""
        linear_x, angular_z = body_velocity(left_speed, right_speed, self.wheel_separation,
                                            self.wheel_radius)
        return Odometry(
            position=np.array([self.x, self.y, 0.0]),
            orientation=frames.yaw_quaternion(self.yaw),
            linear_velocity=np.array([linear_x, 0.0, 0.0]),
            angular_velocity=np.array([0.0, 0.0, angular_z]),
            odometry_frame=odometry_frame, robot_base_frame=robot_base_frame)


def drive_actuator_name(joint_name):
    """Return the name of the wheel actuator the plugin puts on a diff-drive joint."""
    return joint_name + '_drive'


def add_wheel_actuators(spec, config, timestep):
    """Put a wheel servo (add_wheel_servos) on every wheel joint of a drive's config."""
    wheels = [(joint, diameter / 2.0) for left, right, _, diameter in config.wheel_pairs()
              for joint in (left, right)]
    add_wheel_servos(spec, wheels, config.max_wheel_torque, timestep)


def add_wheel_servos(spec, wheels, max_torque, timestep, *, stiffness=1.0):
    """
    Put a torque-limited velocity servo on every wheel joint, and free the joint of friction.

    wheels: (joint name, wheel radius) of each wheel; max_torque: the most each servo gives,
    in N m (infinity: as much as the joint's own effort limit lets it); stiffness: the gain
    as a multiple of the one described below, for a joint held at its speed more firmly (the
    speed error under a load is the load over the gain).

    The servo's activation is the wheel speed set point and its control input is the rate of
    change of that set point, which lets the drive ramp speeds at max_wheel_acceleration
    without touching the controls every physics step.

    MuJoCo treats the servo's damping implicitly only while the torque is below its limit.
    With gain kv = joint inertia / timestep, a torque-limited step can never carry the wheel
    past its set point, so the servo neither chatters nor goes unstable. Each wheel gets an
    armature (motor rotor inertia seen through the gearbox) equal to its share of the robot's
    mass seen at the rim, the usual inertia-matched motor sizing; that raises the gain until
    the wheel follows its set point within a few milliseconds, like a Gazebo joint motor.

    Gazebo's joint motor and the joint's Coulomb friction share one constraint in ODE, and
    the drive's motor replaces the friction: a driven wheel keeps its damping, not its
    <dynamics friction>.
    """
    robot_mass = sum(body.mass for body in spec.bodies)
    for joint_name, radius in wheels:
        joint = spec.joint(joint_name)
        joint.frictionloss = 0.0
        joint.armature = robot_mass * radius ** 2 / len(wheels)
        kv = stiffness * (_inertia_about_axis(joint.parent, joint.axis)
                          + joint.armature) / timestep
        actuator = spec.add_actuator(name=drive_actuator_name(joint_name), target=joint_name)
        actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
        actuator.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.gainprm[0] = kv
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.biasprm[:3] = [0.0, 0.0, -kv]
        if math.isfinite(max_torque):
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.forcerange = [-max_torque, max_torque]
        else:
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_FALSE
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
    A robot's drive at run time: wheel set points, command timeout, odometry.

    Wheel speeds are servo set points held in the actuators' activations; a ramp at the
    acceleration limit runs in MuJoCo by itself, and the drive only acts at its events: a
    ramp's end and the lapse of a command. The ROS face uses command_velocity(), odometry()
    and the config's odometry_frame, robot_base_frame, publish_* flags, update_rate and
    covariance; every drive kind offers the same.
    """

    title = 'diff-drive'
    is_drive = True

    def __init__(self, config, block):
        """Start at rest, with no command and odometry at the origin."""
        super().__init__(config, block)
        pairs = config.wheel_pairs()
        # Per wheel, lefts first: which side (-1 left, +1 right), half the pair's
        # separation, and the wheel's radius.
        self._sides = np.array([-1.0] * len(pairs) + [1.0] * len(pairs))
        self._half_separations = np.array([separation / 2.0 for _, _, separation, _ in pairs] * 2)
        self._radii = np.array([diameter / 2.0 for _, _, _, diameter in pairs] * 2)
        self._joints = config.left_joints + config.right_joints
        self.acceleration = config.max_wheel_acceleration / self._radii  # rad/s^2, per wheel
        self.targets = np.zeros(len(self._joints))
        self.ramp_end = np.full(len(self._joints), math.inf)
        self.expiry = math.inf
        self.commanded_at = None  # simulation time of the command in force, if there is one
        self.encoder = EncoderOdometry(pairs[0][2], pairs[0][3] / 2.0)
        self.origin_position = np.zeros(3)
        self.origin_orientation = np.array(frames.IDENTITY_QUATERNION)

    @classmethod
    def configure(cls, block, robot):
        """Return the DiffDriveConfig of a diff-drive block, in either spelling."""
        return read_diff_drive(block, robot)

    @classmethod
    def build(cls, spec, config, timestep):
        """Put the wheel servos on the robot's spec (see add_wheel_actuators)."""
        add_wheel_actuators(spec, config, timestep)

    def bind(self, world, model):
        """Find the wheel actuators, wheel joints and base body in the compiled model."""
        super().bind(world, model)
        mj_model, config = world.model, self.config
        self._actuator_ids = np.array(
            [model.element_id(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR,
                              drive_actuator_name(joint)) for joint in self._joints], dtype=int)
        self._act_adr = mj_model.actuator_actadr[self._actuator_ids].astype(int)
        base_link = config.robot_base_frame
        if base_link not in model.description.links:
            base_link = model.description.root_link
        self._base_body_id = model.element_id(mj_model, mujoco.mjtObj.mjOBJ_BODY, base_link)
        wheels = [model.element_id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name)
                  for name in (config.left_joint, config.right_joint)]
        self._wheel_qpos_adr = tuple(int(mj_model.jnt_qposadr[wheel]) for wheel in wheels)
        self._wheel_dof_adr = tuple(int(mj_model.jnt_dofadr[wheel]) for wheel in wheels)

    def next_event(self):
        """Return when the next ramp ends or the command lapses."""
        return min(self.expiry, float(self.ramp_end.min()))

    def command_velocity(self, linear_x, angular_z):
        """
        Drive at a body twist until the world's cmd_vel_timeout lapses; return what is done.

        A command that would turn a wheel rim faster than MAX_WHEEL_RIM_SPEED is scaled down
        to that speed, keeping the radius of the turn. NaN or infinity is refused.
        """
        linear_x = validation.finite_number(linear_x, 'linear_x')
        angular_z = validation.finite_number(angular_z, 'angular_z')
        # Scale before the wheel speeds are worked out, so that no sum of huge values overflows.
        fastest_rim = max(abs(linear_x), abs(angular_z) * float(self._half_separations.max()))
        if fastest_rim > MAX_WHEEL_RIM_SPEED:
            scale = MAX_WHEEL_RIM_SPEED / fastest_rim
            linear_x, angular_z = linear_x * scale, angular_z * scale
        rims = linear_x + self._sides * angular_z * self._half_separations
        fastest_rim = float(np.abs(rims).max())
        if fastest_rim > MAX_WHEEL_RIM_SPEED:
            scale = MAX_WHEEL_RIM_SPEED / fastest_rim
            linear_x, angular_z, rims = linear_x * scale, angular_z * scale, rims * scale
        self.integrate_encoders()
        self._set_wheel_targets(rims / self._radii)
        self.commanded_at = self.world.data.time
        self.set_timeout(self.world.cmd_vel_timeout)
        self.world.schedule_event(self.next_event())
        return linear_x, angular_z

    def set_timeout(self, timeout):
        """Let the command in force lapse timeout seconds after it came (0: never)."""
        if self.commanded_at is not None:
            self.expiry = self.commanded_at + timeout if timeout > 0.0 else math.inf

    def _set_wheel_targets(self, speeds):
        """
        Set wheel speed set points, ramped at the drive's acceleration limit if it has one.

        The servo's activation is its speed set point and its control is the set point's rate
        of change, so a ramp needs no work between its start and its end.
        """
        data, timestep = self.world.data, self.world.timestep
        self.targets[:] = speeds
        for index, (actuator, act) in enumerate(zip(self._actuator_ids, self._act_adr)):
            change = self.targets[index] - data.act[act]
            acceleration = self.acceleration[index]
            ramp_steps = (math.floor(abs(change) / (acceleration * timestep))
                          if acceleration > 0.0 else 0)
            if ramp_steps == 0:
                data.act[act] = self.targets[index]
                data.ctrl[actuator] = 0.0
                self.ramp_end[index] = math.inf
            else:
                data.ctrl[actuator] = math.copysign(acceleration, change)
                self.ramp_end[index] = data.time + ramp_steps * timestep

    def update(self, now):
        """End the ramps that are due, and stop the wheels if the command lapsed."""
        data = self.world.data
        for index in np.nonzero(self.ramp_end <= now)[0]:
            data.act[self._act_adr[index]] = self.targets[index]
            data.ctrl[self._actuator_ids[index]] = 0.0
            self.ramp_end[index] = math.inf
        if self.expiry <= now:
            self.integrate_encoders()
            self._set_wheel_targets(np.zeros(len(self.targets)))
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
        self.encoder.reset(*wheel_values(data.qpos, self._wheel_qpos_adr))
        base = self.world.body_state(self._base_body_id)
        self.origin_position = base.position
        self.origin_orientation = base.orientation

    def integrate_encoders(self):
        """Add the wheel turns since the last call to encoder odometry, whoever reads it."""
        self.encoder.update(*wheel_values(self.world.data.qpos, self._wheel_qpos_adr))

    def odometry(self):
        """Return the robot's odometry, from its first pair's encoders or from ground truth."""
        config = self.config
        if config.odometry_source == ODOMETRY_SOURCE_ENCODER:
            self.integrate_encoders()
            return self.encoder.odometry(*wheel_values(self.world.data.qvel,
                                                       self._wheel_dof_adr),
                                         config.odometry_frame, config.robot_base_frame)
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
