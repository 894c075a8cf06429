"""
gz-sim's lidars (<sensor type="gpu_lidar"> and "lidar"), simulation side.

The Classic laser (ray_sensor.py) casts the rays, in one mujoco.mj_multiRay call: a grid of
<vertical><samples> rows of <horizontal><samples> beams (each times its <resolution>), from the
<min_angle> to the <max_angle> of each, read from <lidar> or its older name <ray>. Readings
follow gz-sensors: +inf with no return within <range><max>, -inf at or below <range><min>,
gaussian noise on the others. gz publishes a LaserScan on its topic (ros_gz_bridge keeps the
middle row of a multi-row scan) and the points on <topic>/points; here the points are served
when the scan has more than one row.
"""

from dataclasses import dataclass
import functools
import math

import numpy as np
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.gz_sensor import gz_sensor_fields, GzSensor
from service_tutorial.sim.plugins.ray_sensor import ANGLE_ROUNDING, FULL_TURN
from service_tutorial.sim.plugins.ray_sensor import MAX_SCAN_READINGS, RayConfig, RaySensor
from service_tutorial.sim.plugins.sensor import gaussian_noise, sensor_of
from service_tutorial.sim.validation import quoted

LIDAR_TYPES = ('gpu_lidar', 'lidar')


@dataclass(frozen=True)
class GzLidarConfig(RayConfig):
    """A gz lidar's grid of beams (samples: all of them, rows one after the other)."""

    horizontal_samples: int = 1
    vertical_samples: int = 1
    vertical_min: float = 0.0  # rad, the lowest row, up from the sensor's xy plane
    vertical_max: float = 0.0  # rad, the highest
    robot_name: str = ''  # the model's own name, for its gz topics until it is spawned
    topic: str = None
    gz_frame_id: str = None
    always_on: bool = True
    notes: tuple = ()

    @property
    def angle_increment(self):
        """Return the angle between two beams of a row, as LaserScan has it."""
        count = self.horizontal_samples
        return (self.angle_max - self.angle_min) / (count - 1) if count > 1 else 0.0

    @property
    def vertical_increment(self):
        """Return the angle between two rows."""
        count = self.vertical_samples
        return (self.vertical_max - self.vertical_min) / (count - 1) if count > 1 else 0.0

    @functools.cached_property
    def directions(self):
        """Return the unit vectors of the beams in the sensor frame, row after row."""
        yaw = self.angle_min + self.angle_increment * np.arange(self.horizontal_samples)
        pitch = self.vertical_min + self.vertical_increment * np.arange(self.vertical_samples)
        pitch, yaw = (grid.ravel() for grid in np.meshgrid(pitch, yaw, indexing='ij'))
        return np.stack([np.cos(pitch) * np.cos(yaw), np.cos(pitch) * np.sin(yaw),
                         np.sin(pitch)], axis=1)


def read_config(block, robot):
    """Return the GzLidarConfig of a gz lidar's <sensor>, or refuse what is absurd."""
    sensor = sensor_of(block, LIDAR_TYPES, 'lidar')
    base = 'ray' if any(path.startswith('ray/') for path in sensor.values) else 'lidar'
    counts, angles = {}, {}
    for axis, default in (('horizontal', 640), ('vertical', 1)):
        scan = f'{base}/scan/{axis}/'
        samples = sensor.number(scan + 'samples', default, above=0, whole=True)
        resolution = sensor.number(scan + 'resolution', 1.0, above=0.0)
        if samples * resolution > MAX_SCAN_READINGS + 1:
            raise UrdfError(f'sensor {quoted(sensor.name)} <{scan}samples> {samples} times '
                            f'<resolution> {resolution:g} must give at most '
                            f'{MAX_SCAN_READINGS} readings per scan')
        counts[axis] = max(1, round(samples * resolution))
        angles[axis] = tuple(_angle(sensor, scan + tag) for tag in ('min_angle', 'max_angle'))
        if angles[axis][0] > angles[axis][1]:
            raise UrdfError(f'sensor {quoted(sensor.name)} <{scan}min_angle> '
                            f'{angles[axis][0]:g} is above its <max_angle> {angles[axis][1]:g}')
    readings = counts['horizontal'] * counts['vertical']
    if readings > MAX_SCAN_READINGS:
        raise UrdfError(f'sensor {quoted(sensor.name)} scans {counts["horizontal"]} x '
                        f'{counts["vertical"]} = {readings} beams; at most '
                        f'{MAX_SCAN_READINGS} are cast per scan')
    range_min = sensor.number(f'{base}/range/min', 0.0, minimum=0.0)
    range_max = sensor.number(f'{base}/range/max', None, above=range_min)
    if range_max is None:
        raise UrdfError(f'sensor {quoted(sensor.name)} has no <{base}/range/max>')
    mean, stddev = gaussian_noise(sensor, f'{base}/noise')
    (angle_min, angle_max), (vertical_min, vertical_max) = angles['horizontal'], \
        angles['vertical']
    return GzLidarConfig(
        name=sensor.name, link=sensor.link, position=sensor.position,
        orientation=sensor.orientation, update_rate=sensor.update_rate, samples=readings,
        angle_min=angle_min, angle_max=angle_max, range_min=range_min, range_max=range_max,
        noise_mean=mean, noise_stddev=stddev, horizontal_samples=counts['horizontal'],
        vertical_samples=counts['vertical'], vertical_min=vertical_min,
        vertical_max=vertical_max, **gz_sensor_fields(sensor, robot))


def _angle(sensor, path):
    """Return a scan's angle in rad, refusing one beyond a full turn."""
    angle = sensor.number(path, 0.0)
    if abs(angle) > FULL_TURN + ANGLE_ROUNDING:
        raise UrdfError(f'sensor {quoted(sensor.name)} <{path}> must be within one turn '
                        f'(+-{FULL_TURN:.4f} rad): {angle:g}')
    return angle


class GzLidar(GzSensor, RaySensor):
    """A gz lidar on a robot's link: its scan's ranges, row after row (float32, m)."""

    title = 'lidar'
    kind = 'lidar'

    @classmethod
    def configure(cls, block, robot):
        """Return the GzLidarConfig of the block's <sensor> (see read_config)."""
        return read_config(block, robot)

    def gz_topics(self, model_name, world_name):
        """Return the lidar's gz topics: its scan, and its points for a scan of rows."""
        scan = self.gz_topic(model_name, world_name, 'scan')
        return {'scan': scan,
                'points': scan + '/points' if self.config.vertical_samples > 1 else None}

    def middle_row(self):
        """Return the ranges of the scan's middle row, the one a LaserScan carries."""
        width = self.config.horizontal_samples
        start = self.config.vertical_samples // 2 * width
        return self.ranges[start:start + width]

    def points(self):
        """Return where each beam of the last scan ended, (samples, 3) in the sensor frame."""
        with np.errstate(invalid='ignore'):
            points = self.ranges[:, None] * self.config.directions.astype(np.float32)
        points[~np.isfinite(self.ranges)] = math.inf
        return points


PLUGIN = GzLidar
