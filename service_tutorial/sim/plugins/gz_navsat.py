"""
gz-sim's NavSat (<sensor type="navsat">, the NavSat system), simulation side.

A fix of the sensor's position in the world, turned into latitude, longitude and altitude by
the world's <spherical_coordinates> (geodesy.py, as gz-math does), and its velocity as east,
north and up. The gaussian noise of <navsat><position_sensing> and <velocity_sensing>
(<horizontal> and <vertical>, in m and m/s) goes on the position and velocity before they are
turned. A world without spherical coordinates gives zeros, as gz-sim does. Its topic is
<topic>, else .../sensor/<name>/navsat.
"""

from dataclasses import dataclass

import mujoco
import numpy as np
from service_tutorial.sim.plugins.gz_sensor import gz_sensor_fields, GzSensor
from service_tutorial.sim.plugins.sensor import gaussian_noise, Sensor, sensor_of
from service_tutorial.sim.plugins.sensor import SENSOR_SITE_GROUP, SensorConfig


@dataclass(frozen=True)
class GzNavSatConfig(SensorConfig):
    """A NavSat's noise: (mean, stddev) of position and velocity, horizontal and vertical."""

    position_noise: tuple = ((0.0, 0.0), (0.0, 0.0))  # m: horizontal, vertical
    velocity_noise: tuple = ((0.0, 0.0), (0.0, 0.0))  # m/s
    robot_name: str = ''  # the model's own name, for its gz topics until it is spawned
    topic: str = None
    gz_frame_id: str = None
    always_on: bool = True
    notes: tuple = ()


def read_config(block, robot):
    """Return the GzNavSatConfig of a NavSat's <sensor>, or refuse what is absurd."""
    sensor = sensor_of(block, ('navsat', 'gps'), 'NavSat')
    base = 'gps' if any(path.startswith('gps/') for path in sensor.values) else 'navsat'
    noise = {quantity: tuple(gaussian_noise(sensor, f'{base}/{quantity}_sensing/{axis}/noise')
                             for axis in ('horizontal', 'vertical'))
             for quantity in ('position', 'velocity')}
    return GzNavSatConfig(
        name=sensor.name, link=sensor.link, position=sensor.position,
        orientation=sensor.orientation, update_rate=sensor.update_rate,
        position_noise=noise['position'], velocity_noise=noise['velocity'],
        **gz_sensor_fields(sensor, robot))


class GzNavSat(GzSensor, Sensor):
    """A NavSat on a robot's link: latitude and longitude (deg), altitude (m), velocity (ENU)."""

    title = 'NavSat'
    kind = 'navsat'

    def __init__(self, config, block):
        """Start with no fix."""
        super().__init__(config, block)
        self.latitude = self.longitude = self.altitude = 0.0
        self.velocity = np.zeros(3)  # east, north, up in m/s
        self._twist = np.zeros(6)

    @classmethod
    def configure(cls, block, robot):
        """Return the GzNavSatConfig of the block's <sensor> (see read_config)."""
        return read_config(block, robot)

    @classmethod
    def build(cls, spec, config, timestep):
        """Mark the sensor's pose on its link with a site."""
        spec.body(config.link).add_site(
            name=config.site_name(cls.kind), pos=config.position, quat=config.orientation,
            group=SENSOR_SITE_GROUP)

    def gz_topics(self, model_name, world_name):
        """Return the NavSat's gz topic."""
        return {'navsat': self.gz_topic(model_name, world_name, 'navsat')}

    def read(self):
        """Fix the sensor's position and velocity, with their noise."""
        world = self.world
        position = world.data.site_xpos[self.site_id].copy()
        mujoco.mj_objectVelocity(world.model, world.data, mujoco.mjtObj.mjOBJ_SITE,
                                 self.site_id, self._twist, 0)
        velocity = self._twist[3:].copy()
        position += self._noise(self.config.position_noise)
        velocity += self._noise(self.config.velocity_noise)
        coordinates = world.spherical_coordinates
        if coordinates is None:
            return
        self.latitude, self.longitude, self.altitude = \
            coordinates.spherical_from_local(position)
        self.velocity = coordinates.global_from_local_velocity(velocity)

    def _noise(self, noise):
        (horizontal_mean, horizontal), (vertical_mean, vertical) = noise
        if not (horizontal or vertical or horizontal_mean or vertical_mean):
            return np.zeros(3)
        return self.random.normal([horizontal_mean] * 2 + [vertical_mean],
                                  [horizontal] * 2 + [vertical])


PLUGIN = GzNavSat
