"""
gz-sim's JointPositionController system (gz-sim-joint-position-controller-system), simulation.

A joint driven to the position a Float64 (gz's Double) on its topic commands: <topic>, else
/model/<model>/<sub_topic>, else /model/<model>/joint/<joint>/<joint_index>/cmd_pos; the
first target is <initial_position>. gz's PID pushes with offset - p e - I - d de/dt, e being
the position less the target, within [<cmd_min>, <cmd_max>]: here a MuJoCo actuator of gain 1
whose bias holds the offset, -p times the position and -d times the velocity (MuJoCo treats
the damping implicitly), its control p times the target less the integral term I. I grows by
i_gain e dt within [<i_min>, <i_max>], as gz-math's PID has it, brought up to date every
INTEGRAL_PERIOD of simulation time rather than every step. <use_velocity_commands> and
<use_actuator_msg> are named as not simulated: the force mode is used.
"""

import math

import mujoco
from service_tutorial.sim.plugins.gz_joint_controller import JointCommand
from service_tutorial.sim.plugins.gz_joint_controller import JointCommandConfig
from service_tutorial.sim.plugins.gz_joint_controller import read_joint_command
from service_tutorial.sim.plugins.gz_parameters import GzParameters

# Simulation time between two updates of the PID's integral term, in s.
INTEGRAL_PERIOD = 0.01


class GzJointPositionController(JointCommand):
    """Joints held at a commanded position by gz's PID."""

    title = 'JointPositionController system'
    suffix = 'cmd_pos'

    def __init__(self, config, block):
        """Start with no integral and the initial target."""
        super().__init__(config, block)
        self.integral = 0.0
        self._next_integral = math.inf
        self._qpos_adr = ()

    @classmethod
    def configure(cls, block, robot):
        """Return the JointCommandConfig of a JointPositionController block."""
        parameters = GzParameters(block, 'JointPositionController')
        fields = read_joint_command(
            parameters, robot, initial_tag='initial_position',
            mode_tag='use_velocity_commands',
            pid_defaults={'p_gain': 1.0, 'i_gain': 0.1, 'd_gain': 0.01, 'i_max': 1.0,
                          'i_min': -1.0, 'cmd_max': 1000.0, 'cmd_min': -1000.0,
                          'cmd_offset': 0.0})
        for tag in ('use_velocity_commands', 'use_actuator_msg'):
            if parameters.flag(tag, False):
                parameters.notes.append(f'JointPositionController <{tag}> is not simulated: '
                                        'its PID pushes the joint with a force')
        fields['force_commands'] = True
        return JointCommandConfig(**fields, notes=tuple(parameters.notes))

    @classmethod
    def build(cls, spec, config, timestep):
        """Put the PID's actuator on every joint."""
        for joint in config.mujoco_joints():
            actuator = spec.add_actuator(name=cls.actuator(joint), target=joint)
            actuator.trntype = mujoco.mjtTrn.mjTRN_JOINT
            actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
            actuator.gainprm[0] = 1.0
            actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
            actuator.biasprm[:3] = [config.cmd_offset, -config.p_gain, -config.d_gain]
            actuator.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            actuator.forcerange = [config.cmd_min, config.cmd_max]

    @classmethod
    def actuator(cls, joint):
        """Return the name of the actuator the controller puts on a joint."""
        return joint + '_position'

    def bind(self, world, model):
        """Find the actuators and where the joints' positions are."""
        super().bind(world, model)
        self._qpos_adr = world.model.jnt_qposadr[
            world.model.actuator_trnid[self._actuator_ids, 0]].astype(int)

    def apply(self):
        """Aim every joint at the target, less the integral term."""
        data = self.world.data
        data.ctrl[self._actuator_ids] = self.config.p_gain * self.command_value - self.integral
        if self.config.i_gain:
            self._next_integral = min(self._next_integral, self.world.time + INTEGRAL_PERIOD)
            self.world.schedule_event(self._next_integral)

    def next_event(self):
        """Return when the integral term is next brought up to date."""
        return self._next_integral

    def update(self, now):
        """Add the first joint's error since the last update to the integral term."""
        config = self.config
        error = float(self.world.data.qpos[self._qpos_adr[0]]) - self.command_value
        self.integral = min(max(self.integral + config.i_gain * INTEGRAL_PERIOD * error,
                                config.i_min), config.i_max)
        self._next_integral = self.world.time + INTEGRAL_PERIOD
        self.apply()

    def reset(self):
        """Go back to the initial target, with no integral."""
        self.integral = 0.0
        self._next_integral = math.inf
        super().reset()


PLUGIN = GzJointPositionController
