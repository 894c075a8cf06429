"""
The Gazebo laser plugins (gazebo_ros_laser, ROS 1; gazebo_ros_ray_sensor, ROS 2), simulation side.

A <sensor type="ray"> (or gpu_ray) casts one horizontal fan of rays per scan, all in one
mujoco.mj_multiRay call from the sensor's pose. Like Gazebo's laser it sees collision shapes:
other robots', the floor's and the scenery's, never its own robot's. Readings follow REP 117:
+inf beyond range_max or without a return, -inf at or below range_min; gaussian noise goes on
in-range readings only, which then stay within [range_min, range_max].
"""

from dataclasses import dataclass
import functools
import math

import mujoco
import numpy as np
from service_tutorial.sim.core_logs import core_logger
from service_tutorial.sim.description import COLLISION_GROUP
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.sensor import gaussian_noise
from service_tutorial.sim.plugins.sensor import Sensor
from service_tutorial.sim.plugins.sensor import sensor_of
from service_tutorial.sim.plugins.sensor import SENSOR_SITE_GROUP
from service_tutorial.sim.plugins.sensor import SensorConfig
from service_tutorial.sim.validation import quoted

_logger = core_logger(__name__)

SCAN = 'ray/scan/horizontal/'
# The rays see the floor and scenery of MJCF files (group 0) and every URDF collision shape;
# the robot's own geoms are moved to HIDDEN_GROUP for the length of the cast.
HIDDEN_GROUP = 5
# A scan's beams lie within one turn: each angle within FULL_TURN of the sensor's x axis, and
# the last at most FULL_TURN from the first. ANGLE_ROUNDING lets in +-pi written to three
# decimals (-3.142 to 3.142), as robot files often write a full scan.
FULL_TURN = 2.0 * math.pi
ANGLE_ROUNDING = 1e-3
# The most readings a scan may have (samples x resolution); real lasers give a few thousand.
# A scan is cast on the stepping thread: 20,000 beams took 13 ms here and the world answered
# within 60 ms at 30 scans a second; 100,000 took 40 to 65 ms and answers took 300 ms.
MAX_SCAN_READINGS = 20000
RAY_GEOM_GROUPS = np.array([int(group in (0, COLLISION_GROUP)) for group in range(6)],
                           dtype=np.uint8)


@dataclass(frozen=True)
class RayConfig(SensorConfig):
    """A laser's scan: its beams' angles in the sensor frame, its range and its noise."""

    samples: int  # readings per scan
    angle_min: float  # rad, first beam, counter-clockwise from x
    angle_max: float  # rad, last beam
    range_min: float  # m
    range_max: float  # m
    noise_mean: float  # m, added to in-range readings
    noise_stddev: float  # m

    @property
    def angle_increment(self):
        """Return the angle between two beams, as LaserScan has it."""
        return (self.angle_max - self.angle_min) / (self.samples - 1) if self.samples > 1 \
            else 0.0

    @functools.cached_property
    def directions(self):
        """Return the unit vectors of the beams in the sensor frame, one row each."""
        # Worked out once per robot description, not at every spawn of it.
        angles = self.angle_min + self.angle_increment * np.arange(self.samples)
        return np.stack([np.cos(angles), np.sin(angles), np.zeros(self.samples)], axis=1)


def read_config(block):
    """Return the RayConfig of a laser plugin from the <sensor> it sits in."""
    sensor = sensor_of(block, ('ray', 'gpu_ray'), 'laser')
    samples = sensor.number(SCAN + 'samples', 640, above=0, whole=True)
    resolution = sensor.number(SCAN + 'resolution', 1.0, above=0.0)
    if round(min(samples * resolution, MAX_SCAN_READINGS + 1)) > MAX_SCAN_READINGS:
        raise UrdfError(f'sensor {quoted(sensor.name)} <{SCAN}samples> {samples} times '
                        f'<resolution> {resolution:g} must give at most {MAX_SCAN_READINGS} '
                        'readings per scan')
    # Gazebo reports samples x resolution readings; these are cast, not interpolated.
    readings = max(1, round(samples * resolution))
    angle_min, angle_max = (scan_angle(sensor, tag) for tag in ('min_angle', 'max_angle'))
    if angle_min > angle_max:
        raise UrdfError(f'sensor {quoted(sensor.name)} <{SCAN}min_angle> {angle_min:g} is '
                        f'above its <max_angle> {angle_max:g}')
    if angle_max - angle_min > FULL_TURN + ANGLE_ROUNDING:
        raise UrdfError(f'sensor {quoted(sensor.name)} <{SCAN}min_angle> {angle_min:g} and '
                        f'<max_angle> {angle_max:g} must be at most one turn '
                        f'({FULL_TURN:.4f} rad) apart: {angle_max - angle_min:g} rad')
    range_min = sensor.number('ray/range/min', 0.0, minimum=0.0)
    range_max = sensor.number('ray/range/max', None, above=range_min)
    if range_max is None:
        raise UrdfError(f'sensor {quoted(sensor.name)} has no <ray/range/max>')
    if sensor.number('ray/scan/vertical/samples', 1, above=0, whole=True) > 1:
        _logger.warning('sensor %s: only the horizontal plane of a multi-layer scan is '
                        'simulated', quoted(sensor.name))
    mean, stddev = gaussian_noise(sensor, 'ray/noise')
    return RayConfig(
        name=sensor.name, link=sensor.link, position=sensor.position,
        orientation=sensor.orientation, update_rate=sensor.update_rate,
        samples=readings, angle_min=angle_min, angle_max=angle_max, range_min=range_min,
        range_max=range_max, noise_mean=mean, noise_stddev=stddev)


def scan_angle(sensor, tag):
    """Return a scan's <min_angle> or <max_angle> in rad, refusing one beyond a full turn."""
    angle = sensor.number(SCAN + tag, 0.0)
    if abs(angle) > FULL_TURN + ANGLE_ROUNDING:
        raise UrdfError(f'sensor {quoted(sensor.name)} <{SCAN}{tag}> must be within one turn '
                        f'(+-{FULL_TURN:.4f} rad): {angle:g}')
    return angle


class RaySensor(Sensor):
    """A laser on a robot's link: one scan per reading, in ranges (float32, metres)."""

    title = 'laser'
    kind = 'ray'

    def __init__(self, config, block):
        """Precompute the beams in the sensor frame and the buffers of a cast."""
        super().__init__(config, block)
        self._directions = config.directions
        # Buffers of a cast, made once: the beams in the world frame, what each ray hit.
        self._world_directions = np.zeros((config.samples, 3))
        self._geom_ids = np.zeros(config.samples, dtype=np.int32)
        self._distances = np.zeros(config.samples)
        self._noise = np.zeros(config.samples)
        self.ranges = np.full(config.samples, np.inf, dtype=np.float32)
        self._origin = np.zeros(3)  # where the last scan was cast from, in the world
        self._own_geoms = np.zeros(0, dtype=int)
        self._own_groups = np.zeros(0, dtype=int)

    @classmethod
    def configure(cls, block, robot):
        """Return the RayConfig of the block's <sensor> (see read_config)."""
        return read_config(block)

    @classmethod
    def build(cls, spec, config, timestep):
        """Mark the sensor's pose on its link with a site."""
        spec.body(config.link).add_site(
            name=config.site_name(cls.kind), pos=config.position, quat=config.orientation,
            group=SENSOR_SITE_GROUP)

    def bind(self, world, model):
        """Find the site and every geom of the robot, which the rays must not see."""
        super().bind(world, model)
        mj_model = world.model
        root = mj_model.body_rootid[model.root_id]
        self._own_geoms = np.nonzero(mj_model.body_rootid[mj_model.geom_bodyid] == root)[0]
        self._own_groups = mj_model.geom_group[self._own_geoms].copy()

    def read(self):
        """Cast the scan's rays from the sensor and turn the distances into ranges."""
        mj_model, data, config = self.world.model, self.world.data, self.config
        mujoco.mju_mulMatMatT(self._world_directions, self._directions,
                              data.site_xmat[self.site_id].reshape(3, 3))
        self._origin[:] = data.site_xpos[self.site_id]
        groups = mj_model.geom_group
        groups[self._own_geoms] = HIDDEN_GROUP
        try:
            # flg_static 1: the floor and the scenery are fixed to the world, and seen.
            mujoco.mj_multiRay(mj_model, data, self._origin,
                               self._world_directions.reshape(-1), RAY_GEOM_GROUPS, 1, -1,
                               self._geom_ids, self._distances, None, config.samples,
                               config.range_max)
        finally:
            groups[self._own_geoms] = self._own_groups
        scan_ranges(self._distances, self._geom_ids, config, self.random, self._noise)
        self.ranges[:] = self._distances

    def hit_points(self):
        """Return where the last scan's readings in range lie in the world, (n, 3) in m."""
        hits = np.isfinite(self.ranges)
        return self._origin + self.ranges[hits, None] * self._world_directions[hits]


def scan_ranges(distances, geom_ids, config, random, noise):
    """
    Turn the distances of a scan's rays into its ranges, in place (REP 117).

    No return, or one at or beyond range_max, reads +inf; one at or below range_min reads
    -inf. Readings in between get the gaussian noise, drawn into the buffer noise, and stay
    within the range.
    """
    distances[geom_ids < 0] = math.inf
    distances[distances >= config.range_max] = math.inf
    distances[distances <= config.range_min] = -math.inf
    if config.noise_stddev > 0.0 or config.noise_mean != 0.0:
        random.standard_normal(out=noise)
        noise *= config.noise_stddev
        noise += config.noise_mean
        noise += distances
        # np.clip's own Python costs a scan more than these two passes over it.
        np.maximum(noise, config.range_min, out=noise)
        np.minimum(noise, config.range_max, out=noise)
        np.copyto(distances, noise, where=np.isfinite(distances))


PLUGIN = RaySensor
