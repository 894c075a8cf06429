"""
gz-sim's IMU (<sensor type="imu">, the Imu system), simulation side.

The Classic IMU (imu_sensor.py) measures, with the same per-axis gaussian noise of
<imu><angular_velocity> and <linear_acceleration>: proper acceleration (+9.8 m/s^2 up at rest)
and angular velocity in the sensor frame. Its orientation is gz's: relative to the sensor's
pose at spawn (or at the last reset), unless <orientation_reference_frame><localization> says
ENU, when it is the orientation in the world (whose axes are east, north, up); NED and NWU are
named in a note and taken as ENU. With <enable_orientation> false, no orientation is given
(REP 145: its covariance starts with -1). Its topic is <topic>, else .../sensor/<name>/imu.
"""

from dataclasses import dataclass, fields

import numpy as np
from service_tutorial.sim import frames
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.gz_sensor import gz_sensor_fields, GzSensor
from service_tutorial.sim.plugins.imu_sensor import ImuConfig, ImuSensor
from service_tutorial.sim.plugins.imu_sensor import read_config as read_imu
from service_tutorial.sim.validation import quoted

REFERENCE_FRAMES = ('ENU', 'NED', 'NWU')


@dataclass(frozen=True)
class GzImuConfig(ImuConfig):
    """A gz IMU: the Classic one's noise, and where its orientation is measured from."""

    enable_orientation: bool = True
    world_reference: bool = False  # the orientation in the world, not from the initial pose
    robot_name: str = ''  # the model's own name, for its gz topics until it is spawned
    topic: str = None
    gz_frame_id: str = None
    always_on: bool = True
    notes: tuple = ()


def read_config(block, robot):
    """Return the GzImuConfig of a gz IMU's <sensor>, or refuse what is absurd."""
    classic = read_imu(block, robot)
    sensor = block.sensor
    gz_fields = gz_sensor_fields(sensor, robot)
    notes = list(gz_fields.pop('notes'))
    enable = (sensor.text('imu/enable_orientation') or 'true').lower()
    if enable not in ('true', 'false', '1', '0'):
        raise UrdfError(f'sensor {quoted(sensor.name)} <imu/enable_orientation> must be true '
                        f'or false: {quoted(enable)}')
    reference = sensor.text('imu/orientation_reference_frame/localization')
    if reference is not None and reference.upper() not in REFERENCE_FRAMES:
        raise UrdfError(f'sensor {quoted(sensor.name)} <imu/orientation_reference_frame/'
                        f'localization> must be one of {", ".join(REFERENCE_FRAMES)}: '
                        f'{quoted(reference)}')
    if reference is not None and reference.upper() != 'ENU':
        notes.append(f'sensor {quoted(sensor.name)}: only the ENU orientation reference is '
                     f'simulated; {reference} is taken as ENU')
    return GzImuConfig(
        **{field.name: getattr(classic, field.name) for field in fields(ImuConfig)},
        enable_orientation=enable in ('true', '1'), world_reference=reference is not None,
        notes=tuple(notes), **gz_fields)


class GzImu(GzSensor, ImuSensor):
    """A gz IMU on a robot's link; its orientation from its initial pose, as gz's."""

    title = 'IMU'

    def __init__(self, config, block):
        """Start with the world's axes as the initial orientation."""
        super().__init__(config, block)
        self._initial = np.array([1.0, 0.0, 0.0, 0.0])

    @classmethod
    def configure(cls, block, robot):
        """Return the GzImuConfig of the block's <sensor> (see read_config)."""
        return read_config(block, robot)

    def gz_topics(self, model_name, world_name):
        """Return the IMU's gz topic."""
        return {'imu': self.gz_topic(model_name, world_name, 'imu')}

    def reset(self):
        """Measure the orientation from the sensor's pose now, at rest."""
        super().reset()
        body = self.world.model.site_bodyid[self.site_id]
        link = self.world.body_state(body)
        _, self._initial = frames.compose(link.position, link.orientation,
                                          self.config.position, self.config.orientation)

    def read(self):
        """Measure as the Classic IMU, with the orientation gz gives."""
        super().read()
        if not self.config.world_reference:
            _, self.orientation = frames.relative(np.zeros(3), self._initial, np.zeros(3),
                                                  self.orientation)


PLUGIN = GzImu
