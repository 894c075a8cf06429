"""
The Gazebo IMU plugins (gazebo_ros_imu, ROS 1; gazebo_ros_imu_sensor, ROS 2), simulation side.

MuJoCo measures: an accelerometer, a gyro and a frame orientation sensor on a site of the
link. The accelerometer reads proper acceleration, so an IMU at rest reads +9.81 m/s^2 up
(REP 145), whichever plugin it stands in for; ROS 1's gazebo_ros_imu reported no gravity.

ROS 2 writes the IMU as a <sensor type="imu"> with per-axis gaussian noise
(<imu><angular_velocity><x><noise>, the same for <linear_acceleration>); ROS 1 as a model
plugin in a robot-wide <gazebo> block, on the link its <bodyName> names, with one
<gaussianNoise> for every axis and its own <updateRate>.
"""

from dataclasses import dataclass

import mujoco
import numpy as np
from service_tutorial.sim.description import check_update_rate
from service_tutorial.sim.description import parse_numbers
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.sensor import check_frame_names
from service_tutorial.sim.plugins.sensor import gaussian_noise
from service_tutorial.sim.plugins.sensor import Sensor
from service_tutorial.sim.plugins.sensor import sensor_of
from service_tutorial.sim.plugins.sensor import SENSOR_SITE_GROUP
from service_tutorial.sim.plugins.sensor import SensorConfig
from service_tutorial.sim.validation import quoted

ROS1_FILENAME = 'gazebo_ros_imu.'
# MuJoCo sensor type of each measured quantity, in the order of IMU_CHANNELS.
IMU_CHANNELS = ('orientation', 'angular_velocity', 'linear_acceleration')
_SENSOR_TYPES = (mujoco.mjtSensor.mjSENS_FRAMEQUAT, mujoco.mjtSensor.mjSENS_GYRO,
                 mujoco.mjtSensor.mjSENS_ACCELEROMETER)


@dataclass(frozen=True)
class ImuConfig(SensorConfig):
    """An IMU's gaussian noise, per axis, and how its covariances are reported."""

    angular_velocity_noise: tuple  # ((mean, stddev) for x, y, z), rad/s
    linear_acceleration_noise: tuple  # ((mean, stddev) for x, y, z), m/s^2
    orientation_variance: float  # reported on the orientation covariance's diagonal (rad^2)

    def sensor_name(self, channel):
        """Return the name of the MuJoCo sensor that measures one of IMU_CHANNELS."""
        return f'{self.site_name("imu")}:{channel}'


def is_ros1_block(block):
    """Return True for gazebo_ros's ROS 1 model plugin (libgazebo_ros_imu.so)."""
    return ROS1_FILENAME in block.filename


def read_config(block, robot):
    """Return the ImuConfig of an IMU plugin block, in either generation."""
    if is_ros1_block(block):
        return _ros1_config(block, robot)
    sensor = sensor_of(block, ('imu',), 'IMU')
    noise = {}
    for channel in ('angular_velocity', 'linear_acceleration'):
        noise[channel] = tuple(gaussian_noise(sensor, f'imu/{channel}/{axis}/noise')
                               for axis in 'xyz')
    return ImuConfig(
        name=sensor.name, link=sensor.link, position=sensor.position,
        orientation=sensor.orientation, update_rate=sensor.update_rate,
        angular_velocity_noise=noise['angular_velocity'],
        linear_acceleration_noise=noise['linear_acceleration'], orientation_variance=0.0)


def _ros1_config(block, robot):
    where = f'IMU plugin {quoted(block.name)}'
    if block.sensor is not None:
        raise UrdfError(f'{where} ({block.filename}) is a model plugin: it belongs in a '
                        'robot-wide <gazebo> block, not in a <sensor>')
    if not block.name:
        raise UrdfError(f'an IMU plugin ({block.filename}) has no name')
    link = block.text('bodyName')
    if not link:
        raise UrdfError(f'{where} has no <bodyName>')
    if link not in {robot_link.name for robot_link in robot.links}:
        raise UrdfError(f'{where} <bodyName> {quoted(link)} is not a link of the robot')
    check_frame_names(block)
    sigma = _number(block, 'gaussianNoise', 0.0)
    offset = _vector(block, 'xyzOffset')
    rpy = _vector(block, 'rpyOffset')  # the lesson's <rpyOffsets> is not read, as in ROS 1
    orientation = np.zeros(4)
    mujoco.mju_euler2Quat(orientation, np.array(rpy), 'XYZ')
    return ImuConfig(
        name=block.name, link=link, position=offset,
        orientation=tuple(orientation.tolist()),
        update_rate=check_update_rate(_number(block, 'updateRate', 0.0),
                                      f'{where} <updateRate>'),
        angular_velocity_noise=((0.0, sigma),) * 3,
        linear_acceleration_noise=((0.0, sigma),) * 3, orientation_variance=sigma ** 2)


def _number(block, tag, default):
    text = block.text(tag)
    if text is None:
        return default
    values = parse_numbers(text, f'IMU plugin {quoted(block.name)} <{tag}>')
    if len(values) != 1 or values[0] < 0.0:
        raise UrdfError(f'IMU plugin {quoted(block.name)} <{tag}> must be one number of at '
                        f'least 0: {quoted(text)}')
    return values[0]


def _vector(block, tag):
    text = block.text(tag, '0 0 0')
    values = parse_numbers(text, f'IMU plugin {quoted(block.name)} <{tag}>')
    if len(values) != 3:
        raise UrdfError(f'IMU plugin {quoted(block.name)} <{tag}> must be three numbers: '
                        f'{quoted(text)}')
    return tuple(values)


class ImuSensor(Sensor):
    """
    An IMU on a robot's link.

    Each reading holds orientation (w, x, y, z) in the world frame, angular_velocity (rad/s)
    and linear_acceleration (m/s^2) in the sensor frame, with their noise.
    """

    title = 'IMU'
    kind = 'imu'

    def __init__(self, config, block):
        """Start with no reading and the noise of each axis as arrays."""
        super().__init__(config, block)
        self.orientation = np.array([1.0, 0.0, 0.0, 0.0])
        self.angular_velocity = np.zeros(3)
        self.linear_acceleration = np.zeros(3)
        self._noise = {channel: np.array(getattr(config, channel + '_noise'), dtype=float)
                       for channel in ('angular_velocity', 'linear_acceleration')}
        self._addresses = ()

    @classmethod
    def configure(cls, block, robot):
        """Return the ImuConfig of the block (see read_config)."""
        return read_config(block, robot)

    @classmethod
    def build(cls, spec, config, timestep):
        """Put a site at the IMU's pose and MuJoCo's three sensors on it."""
        site_name = config.site_name(cls.kind)
        spec.body(config.link).add_site(name=site_name, pos=config.position,
                                        quat=config.orientation, group=SENSOR_SITE_GROUP)
        for channel, sensor_type in zip(IMU_CHANNELS, _SENSOR_TYPES):
            spec.add_sensor(name=config.sensor_name(channel), type=sensor_type,
                            objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site_name)

    def bind(self, world, model):
        """Find where MuJoCo writes the three measurements."""
        super().bind(world, model)
        self._addresses = tuple(
            int(world.model.sensor_adr[model.element_id(
                world.model, mujoco.mjtObj.mjOBJ_SENSOR, self.config.sensor_name(channel))])
            for channel in IMU_CHANNELS)

    def read(self):
        """Copy MuJoCo's measurements of the last step and add the noise."""
        data = self.world.data.sensordata
        orientation, gyro, accelerometer = self._addresses
        self.orientation = data[orientation:orientation + 4].copy()
        self.angular_velocity = self._noisy(data[gyro:gyro + 3], 'angular_velocity')
        self.linear_acceleration = self._noisy(data[accelerometer:accelerometer + 3],
                                               'linear_acceleration')

    def _noisy(self, values, channel):
        noise = self._noise[channel]
        if not noise.any():
            return values.copy()
        return values + self.random.normal(noise[:, 0], noise[:, 1])

    def covariance(self, channel):
        """Return the diagonal of a channel's covariance: the variance of its noise."""
        if channel == 'orientation':
            return np.full(3, self.config.orientation_variance)
        return self._noise[channel][:, 1] ** 2


PLUGIN = ImuSensor
