"""
gz-sim's DiffDrive system (gz-sim-diff-drive-system), simulation side.

The wheels turn on the servos of Gazebo Classic's drive (diff_drive.add_wheel_servos): speed set
points held in the actuators' activations, each wheel's torque bounded by its joint's effort
limit, as dartsim's velocity servo is. A command (linear x, angular z) is held until the next
one, with no timeout; each speed is limited as gz-math's SpeedLimiter limits it
(speed_limits.py): a ramp at an acceleration limit runs in MuJoCo by itself and the drive acts
only where it ends, while jerk limits are applied step by step. Every listed joint of a side
turns at that side's speed. Odometry integrates the first left and right wheel joints from
where the robot was at spawn (0, 0, 0), as gz's DiffDriveOdometry does, and goes to the
drive's listener (the ROS face) every 1/odom_publish_frequency s of simulation time. Its
twist comes from the wheels' speeds at that instant, where gz averages its last ten steps.
The topics and frames keep gz's names (gz_topics(), odometry_frame, base_frame).
"""

from dataclasses import dataclass, field
import math

import mujoco
import numpy as np
from service_tutorial.sim import validation
from service_tutorial.sim.description import MAX_SIZE
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import gz_names
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.plugins.diff_drive import add_wheel_servos
from service_tutorial.sim.plugins.diff_drive import drive_actuator_name, EncoderOdometry
from service_tutorial.sim.plugins.diff_drive import MAX_WHEEL_RIM_SPEED, wheel_values
from service_tutorial.sim.plugins.gz_parameters import GzParameters
from service_tutorial.sim.plugins.speed_limits import KINDS, read_limits, SpeedLimits
from service_tutorial.sim.validation import quoted

# The tags gz's DiffDrive reads; any other is named in a note (TurtleBot3's model writes
# odom_publisher_frequency, which gz ignores).
PARAMETERS = {'left_joint', 'right_joint', 'wheel_separation', 'wheel_radius',
              'odom_publish_frequency', 'topic', 'odom_topic', 'tf_topic', 'frame_id',
              'child_frame_id'} | {f'{end}_{axis}{kind}' for end in ('min', 'max')
                                   for axis in ('', 'linear_', 'angular_') for kind in KINDS}


@dataclass(frozen=True)
class GzDiffDriveConfig:
    """A DiffDrive block's parameters, with gz's defaults."""

    robot_name: str  # the model's own name: its gz topics' until it is spawned under another
    left_joints: tuple
    right_joints: tuple
    wheel_separation: float = 1.0  # m
    wheel_radius: float = 0.2  # m
    linear: SpeedLimits = field(default_factory=SpeedLimits)  # m/s, m/s^2, m/s^3
    angular: SpeedLimits = field(default_factory=SpeedLimits)  # rad/s...
    odom_publish_frequency: float = 50.0  # Hz of simulation time; 0 or less: every step
    topic: str = None  # the valid gz topics the block gives; None: gz's default
    odom_topic: str = None
    tf_topic: str = None
    frame_id: str = None  # the frames it gives; None: gz's <model>/odom, <model>/<link>
    child_frame_id: str = None
    notes: tuple = ()

    def wheels(self):
        """Return (joint, radius) of every wheel, lefts first."""
        return [(joint, self.wheel_radius) for joint in self.left_joints + self.right_joints]


def read_config(block, robot):
    """Return the GzDiffDriveConfig of a DiffDrive block of a robot, or refuse it."""
    parameters = GzParameters(block, 'DiffDrive')
    left = parameters.joints('left_joint', robot)
    right = parameters.joints('right_joint', robot)
    kinds = {joint.name: joint.type for joint in robot.joints}
    for name in left + right:
        if kinds[name] not in ('revolute', 'continuous'):
            raise UrdfError(f'DiffDrive wheel joint {quoted(name)} is {kinds[name]}, not '
                            'revolute or continuous')
    if set(left) & set(right):
        raise UrdfError(f'DiffDrive names joint {quoted(sorted(set(left) & set(right))[0])} '
                        'as both a left and a right wheel')
    for tag in block.parameters:
        if tag not in PARAMETERS:
            parameters.notes.append(f"DiffDrive <{tag}> is no parameter of gz-sim's "
                                    'DiffDrive; it is ignored, as gz-sim ignores it')
    return GzDiffDriveConfig(
        robot_name=robot.name, left_joints=left, right_joints=right,
        wheel_separation=parameters.number('wheel_separation', 1.0, above=0.0, maximum=MAX_SIZE),
        wheel_radius=parameters.number('wheel_radius', 0.2, above=0.0, maximum=MAX_SIZE),
        linear=read_limits(parameters, 'linear'), angular=read_limits(parameters, 'angular'),
        odom_publish_frequency=parameters.rate('odom_publish_frequency', 50.0),
        topic=parameters.topic('topic'), odom_topic=parameters.topic('odom_topic'),
        tf_topic=parameters.topic('tf_topic'), frame_id=parameters.frame('frame_id'),
        child_frame_id=parameters.frame('child_frame_id'), notes=tuple(parameters.notes))


class GzDiffDrive(Plugin):
    """A robot's DiffDrive at run time: held command, limited speeds, wheel odometry."""

    title = 'DiffDrive system'
    is_drive = True
    is_gz_system = True

    def __init__(self, config, block):
        """Start at rest, with no command and odometry at the origin."""
        super().__init__(config, block)
        self._sides = np.array([-1.0] * len(config.left_joints)
                               + [1.0] * len(config.right_joints))
        self._limits = (config.linear, config.angular)
        self._stepwise = config.linear.jerk_limited or config.angular.jerk_limited
        self.target = (0.0, 0.0)  # the command in force: linear x m/s, angular z rad/s
        self.enabled = True
        self._speeds = (0.0, 0.0)  # the limited speeds at the last change of their rates
        self.listener = None  # called with the drive at each odometry update
        self.encoder = EncoderOdometry(config.wheel_separation, config.wheel_radius)
        self.odometry_frame = self.base_frame = ''
        self._ramps = ()
        self._history = ((0.0, 0.0), (0.0, 0.0))  # jerk limits: (speed, the one before) per axis
        self._next_change = self._next_odometry = math.inf

    @classmethod
    def configure(cls, block, robot):
        """Return the GzDiffDriveConfig of the block (see read_config)."""
        return read_config(block, robot)

    @classmethod
    def build(cls, spec, config, timestep):
        """Put a servo on every wheel, bounded by its joint's effort limit."""
        add_wheel_servos(spec, config.wheels(), math.inf, timestep)

    def gz_topics(self, model_name):
        """Return the drive's gz topics for a model of that name, by role."""
        config = self.config
        return {
            'cmd_vel': gz_names.first_valid_topic(
                config.topic, gz_names.model_topic(model_name, 'cmd_vel')),
            'enable': gz_names.valid_topic(gz_names.model_topic(model_name, 'enable')),
            'odometry': gz_names.first_valid_topic(
                config.odom_topic, gz_names.model_topic(model_name, 'odometry')),
            'tf': gz_names.first_valid_topic(
                config.tf_topic, gz_names.model_topic(model_name, 'tf'))}

    def bind(self, world, model):
        """Find the wheel servos and the first wheels' joints; name the odometry's frames."""
        super().bind(world, model)
        mj_model, config = world.model, self.config
        self._actuator_ids = np.array(
            [model.element_id(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR, drive_actuator_name(joint))
             for joint, _ in config.wheels()], dtype=int)
        self._act_adr = mj_model.actuator_actadr[self._actuator_ids].astype(int)
        wheels = [model.element_id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name)
                  for name in (config.left_joints[0], config.right_joints[0])]
        self._wheel_qpos_adr = tuple(int(mj_model.jnt_qposadr[wheel]) for wheel in wheels)
        self._wheel_dof_adr = tuple(int(mj_model.jnt_dofadr[wheel]) for wheel in wheels)
        self.odometry_frame = config.frame_id or gz_names.model_frame(model.name, 'odom')
        self.base_frame = config.child_frame_id or gz_names.model_frame(
            model.name, model.description.root_link)

    @property
    def odometry_period(self):
        """Return the simulation time between two odometry updates: at least one step."""
        frequency = self.config.odom_publish_frequency
        return max(self.world.timestep, 1.0 / frequency if frequency > 0.0 else 0.0)

    def next_event(self):
        """Return when the speeds next change their rate, or odometry is due."""
        return min(self._next_change, self._next_odometry)

    def command_velocity(self, linear_x, angular_z):
        """
        Hold a body twist as the command until the next; return what is commanded.

        A command that would turn a wheel rim faster than MAX_WHEEL_RIM_SPEED is scaled down
        to that speed, keeping the radius of the turn; NaN or infinity is refused. While the
        drive is disabled, commands are ignored.
        """
        linear_x = validation.finite_number(linear_x, 'linear_x')
        angular_z = validation.finite_number(angular_z, 'angular_z')
        fastest_rim = abs(linear_x) + abs(angular_z) * self.config.wheel_separation / 2.0
        if fastest_rim > MAX_WHEEL_RIM_SPEED:
            scale = MAX_WHEEL_RIM_SPEED / fastest_rim
            linear_x, angular_z = linear_x * scale, angular_z * scale
        if self.enabled:
            self.target = (linear_x, angular_z)
            self._follow()
        return linear_x, angular_z

    def set_enabled(self, enabled):
        """Enable or disable the drive, as /model/<model>/enable does: disabled, it stops."""
        self.enabled = bool(enabled)
        if not self.enabled:
            self.target = (0.0, 0.0)
            self._follow()

    def _follow(self):
        """Start following the target from now: a ramp per speed, or the first limited step."""
        self.integrate_encoders()
        if self._stepwise:
            self._limit_step()
        else:
            time, step = self.world.time, self.world.timestep
            speeds, _ = self._ramped()
            self._ramps = tuple(limits.ramp(speed, goal, time, step) for limits, speed, goal
                                in zip(self._limits, speeds, self.target))
            self._apply_ramps()
        self.world.schedule_event(self.next_event())

    @property
    def speeds(self):
        """Return the limited speeds the wheels turn at now: linear m/s, angular rad/s."""
        return self._speeds if self._stepwise else self._ramped()[0]

    def _ramped(self):
        """Return the speeds their ramps have reached now, and how fast they change (per s)."""
        if not self._ramps:
            return self._speeds, (0.0, 0.0)
        time, half_step = self.world.time, 0.5 * self.world.timestep
        ramping = [time < ramp.end - half_step for ramp in self._ramps]
        return (tuple(ramp.start + ramp.rate * (time - ramp.begin) if going else ramp.target
                      for ramp, going in zip(self._ramps, ramping)),
                tuple(ramp.rate if going else 0.0 for ramp, going in zip(self._ramps, ramping)))

    def _apply_ramps(self):
        """Set the wheels' set points and their rates of change from the speeds' ramps."""
        self._speeds, rates = self._ramped()
        self._set_wheels(self._speeds, rates)
        self._next_change = min((ramp.end for ramp, rate in zip(self._ramps, rates) if rate),
                                default=math.inf)

    def _limit_step(self):
        """Limit the speeds for the next step, jerk first, as gz-math does at each step."""
        step = self.world.timestep
        history, speeds, settled = [], [], True
        for limits, goal, (previous, before) in zip(self._limits, self.target, self._history):
            speed = limits.limit(goal, previous, before, step)
            history.append((speed, previous))
            speeds.append(speed)
            settled = settled and limits.limit(goal, speed, speed, step) == speed == previous
        self._history, self._speeds = tuple(history), tuple(speeds)
        self._set_wheels(self._speeds, (0.0, 0.0))
        self._next_change = math.inf if settled else self.world.time + step

    def _set_wheels(self, speeds, rates):
        """Turn every wheel at its side's speed, changing at its side's rate (per s)."""
        data, config = self.world.data, self.config
        half_track = self._sides * config.wheel_separation / 2.0
        data.act[self._act_adr] = (speeds[0] + half_track * speeds[1]) / config.wheel_radius
        data.ctrl[self._actuator_ids] = (rates[0] + half_track * rates[1]) / config.wheel_radius

    def update(self, now):
        """Change the wheels' speeds where a limit says, and hand on odometry when it is due."""
        if self._next_change <= now:
            if self._stepwise:
                self._limit_step()
            else:
                self._apply_ramps()
        if self._next_odometry <= now:
            self.integrate_encoders()
            self._next_odometry += self.odometry_period
            if self._next_odometry <= now:  # late, after a reset of time: go on from now
                self._next_odometry = self.world.time + self.odometry_period
            if self.listener is not None:
                self.listener(self)

    def reset(self):
        """Stop the wheels at once, drop the command and start odometry at the origin."""
        self.target, self._speeds = (0.0, 0.0), (0.0, 0.0)
        self._ramps, self._history = (), ((0.0, 0.0), (0.0, 0.0))
        self._next_change = math.inf
        self._set_wheels((0.0, 0.0), (0.0, 0.0))
        self.encoder.reset(*wheel_values(self.world.data.qpos, self._wheel_qpos_adr))
        self._next_odometry = self.world.time + self.odometry_period

    def integrate_encoders(self):
        """Add the first wheels' turns since the last call to the odometry."""
        self.encoder.update(*wheel_values(self.world.data.qpos, self._wheel_qpos_adr))

    def odometry(self):
        """Return the wheel odometry: planar pose from spawn, twist in the base frame."""
        self.integrate_encoders()
        return self.encoder.odometry(*wheel_values(self.world.data.qvel, self._wheel_dof_adr),
                                     self.odometry_frame, self.base_frame)


PLUGIN = GzDiffDrive
