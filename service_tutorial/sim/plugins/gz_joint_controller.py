"""
gz-sim's JointController system (gz-sim-joint-controller-system), simulation side.

A joint driven at the speed a Float64 (gz's Double) on its topic commands: <topic>, else
/model/<model>/<sub_topic>, else /model/<model>/joint/<joint>/cmd_vel, named after the first
<joint_name>; every joint it names turns at that speed, from <initial_velocity>. The speed is
held by the drives' servo (diff_drive.add_wheel_servos), as gz sets a joint's velocity; with
<use_force_commands>, gz's PID on the speed becomes a MuJoCo velocity actuator of gain
<p_gain>, its force within [<cmd_min>, <cmd_max>] (its integral and derivative terms, 0 by
default, are named as not simulated). JointCommand, the base of this and the position
controller, holds what both share: the joints, the topic, the command taken by command().
"""

from dataclasses import dataclass
import math

import mujoco
import numpy as np
from service_tutorial.sim import validation
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import gz_names
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.plugins.diff_drive import add_wheel_servos, drive_actuator_name
from service_tutorial.sim.plugins.gz_parameters import GzParameters

# The fastest a command may turn or slide a joint, in rad/s or m/s; faster ones are cut.
MAX_JOINT_SPEED = 1000.0
# The largest gain or force limit taken; beyond it a joint would only break the physics.
MAX_GAIN = 1e9
# gz sets a joint's velocity outright: its servo is a hundred times as firm as a wheel's,
# which MuJoCo's implicit damping keeps stable (unless the joint's effort limit stops it).
SERVO_STIFFNESS = 100.0


@dataclass(frozen=True)
class JointCommandConfig:
    """What a joint controller drives and where its commands come from."""

    robot_name: str
    joint_names: tuple  # as the robot file names them
    joint_index: int = 0  # the axis of a joint with two (universal, revolute2)
    topic: str = None  # the valid gz topic the block gives; None: gz's default
    sub_topic: str = None  # the topic below /model/<model>/ it gives instead
    initial: float = 0.0  # the first command: speed, or position
    p_gain: float = 1.0
    i_gain: float = 0.0
    d_gain: float = 0.0
    i_min: float = -1.0
    i_max: float = 1.0
    cmd_min: float = -1000.0
    cmd_max: float = 1000.0
    cmd_offset: float = 0.0
    force_commands: bool = False  # JointController: a PID on the speed, not the speed itself
    notes: tuple = ()

    def mujoco_joints(self):
        """Return the names of the MuJoCo joints driven: a second axis is '<joint>_axis2'."""
        return tuple(name + ('_axis2' if self.joint_index == 1 else '')
                     for name in self.joint_names)


def read_joint_command(parameters, robot, *, initial_tag, pid_defaults, mode_tag):
    """Return the fields of a JointCommandConfig a joint controller's block gives."""
    joints = parameters.joints('joint_name', robot)
    title = parameters.title
    index = parameters.number('joint_index', 0, minimum=0, maximum=1)
    kinds = {joint.name: joint.type for joint in robot.joints}
    if index not in (0, 1):
        raise UrdfError(f'{title} <joint_index> must be 0 or 1: {index:g}')
    if index == 1 and any(kinds[name] not in ('universal', 'revolute2') for name in joints):
        raise UrdfError(f'{title} <joint_index> 1 names a second axis, which only universal '
                        'and revolute2 joints have')
    gains = {tag: parameters.number(tag, default, minimum=-MAX_GAIN, maximum=MAX_GAIN)
             for tag, default in pid_defaults.items()}
    for low, high in (('i_min', 'i_max'), ('cmd_min', 'cmd_max')):
        if gains[low] > gains[high]:
            raise UrdfError(f'{title} <{low}> {gains[low]:g} is above its <{high}> '
                            f'{gains[high]:g}')
    return dict(robot_name=robot.name, joint_names=joints, joint_index=int(index),
                topic=parameters.topic('topic'),
                sub_topic=parameters.text('sub_topic') or None,
                initial=parameters.number(initial_tag, 0.0, minimum=-MAX_JOINT_SPEED,
                                          maximum=MAX_JOINT_SPEED),
                force_commands=parameters.flag(mode_tag, False), **gains)


class JointCommand(Plugin):
    """A joint controller: holds the last command for its joints; each kind applies it."""

    single = False
    suffix = 'cmd_vel'  # the end of gz's default topic
    is_gz_system = True

    def __init__(self, config, block):
        """Start at the initial command."""
        super().__init__(config, block)
        self.command_value = config.initial
        self._actuator_ids = np.zeros(0, dtype=int)

    def gz_topics(self, model_name):
        """Return the controller's gz topic for a model of that name."""
        config = self.config
        joint = config.joint_names[0]
        default = (gz_names.model_topic(model_name, 'joint', joint, str(config.joint_index),
                                        self.suffix) if self.suffix == 'cmd_pos'
                   else gz_names.model_topic(model_name, 'joint', joint, self.suffix))
        sub_topic = config.sub_topic and gz_names.model_topic(model_name, config.sub_topic)
        return {'command': gz_names.first_valid_topic(config.topic, sub_topic, default)}

    def bind(self, world, model):
        """Find the controller's actuators, one per joint."""
        super().bind(world, model)
        self._actuator_ids = np.array(
            [model.element_id(world.model, mujoco.mjtObj.mjOBJ_ACTUATOR, self.actuator(joint))
             for joint in self.config.mujoco_joints()], dtype=int)

    @classmethod
    def actuator(cls, joint):
        """Return the name of the actuator the controller puts on a joint."""
        return drive_actuator_name(joint)

    def command(self, value):
        """Take a new speed or position for the joints; return the value applied."""
        value = validation.finite_number(value, 'command')
        value = max(-MAX_JOINT_SPEED, min(MAX_JOINT_SPEED, value))
        self.command_value = value
        self.apply()
        return value

    def apply(self):
        """Drive the joints at the command in force (each kind says how)."""
        raise NotImplementedError

    def reset(self):
        """Go back to the initial command."""
        self.command_value = self.config.initial
        self.apply()


class GzJointController(JointCommand):
    """Joints driven at a commanded speed, or by a PID on it (use_force_commands)."""

    title = 'JointController system'

    @classmethod
    def configure(cls, block, robot):
        """Return the JointCommandConfig of a JointController block."""
        parameters = GzParameters(block, 'JointController')
        fields = read_joint_command(
            parameters, robot, initial_tag='initial_velocity', mode_tag='use_force_commands',
            pid_defaults={'p_gain': 1.0, 'i_gain': 0.0, 'd_gain': 0.0, 'i_max': 1.0,
                          'i_min': -1.0, 'cmd_max': 1000.0, 'cmd_min': -1000.0,
                          'cmd_offset': 0.0})
        if fields['force_commands']:
            for tag in ('i_gain', 'd_gain', 'cmd_offset'):
                if fields[tag]:
                    parameters.notes.append(f'JointController <{tag}> is not simulated: its '
                                            'PID has a proportional term only here')
        return JointCommandConfig(**fields, notes=tuple(parameters.notes))

    @classmethod
    def build(cls, spec, config, timestep):
        """Put a speed servo (or a velocity actuator for force commands) on every joint."""
        joints = config.mujoco_joints()
        if not config.force_commands:
            add_wheel_servos(spec, [(joint, 0.0) for joint in joints], math.inf, timestep,
                             stiffness=SERVO_STIFFNESS)
            return
        for joint in joints:
            actuator = spec.add_actuator(name=cls.actuator(joint), target=joint)
            actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
            actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            actuator.gainprm[0] = config.p_gain
            actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
            actuator.biasprm[:3] = [0.0, 0.0, -config.p_gain]
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.forcerange = [config.cmd_min, config.cmd_max]

    def apply(self):
        """Set every joint's speed set point to the command."""
        data = self.world.data
        if self.config.force_commands:
            data.ctrl[self._actuator_ids] = self.command_value
        else:
            data.act[self.world.model.actuator_actadr[self._actuator_ids]] = self.command_value
            data.ctrl[self._actuator_ids] = 0.0


PLUGIN = GzJointController
