"""
gz-sim's OdometryPublisher system (gz-sim-odometry-publisher-system), simulation side.

Ground-truth odometry: the pose of the model's frame in the world (its root link), moved by
<xyz_offset> and <rpy_offset>, in the frames <odom_frame> (<model>/odom) and <robot_base_frame>
(<model>/base_footprint); with <dimensions> 2, its height is 0. Its twist is the root link's
velocity in its own frame (gz differences the poses of its last steps), with <gaussian_noise>
added to each component. It goes to the listener (the ROS face) every
1/odom_publish_frequency s of simulation time, for odom_topic (/model/<model>/odometry),
odom_covariance_topic (/model/<model>/odometry_with_covariance, the noise's variance on both
covariances' diagonals) and tf_topic (/model/<model>/pose).
"""

from dataclasses import dataclass
import functools
import math
import zlib

import numpy as np
from service_tutorial.sim import frames
from service_tutorial.sim.description import MAX_SIZE
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import gz_names
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.plugins.diff_drive import Odometry
from service_tutorial.sim.plugins.gz_parameters import GzParameters

# The largest <gaussian_noise> (m/s, rad/s) taken: beyond it the twist says nothing.
MAX_NOISE = 1000.0


@dataclass(frozen=True)
class GzOdometryConfig:
    """An OdometryPublisher block's parameters, with gz's defaults."""

    robot_name: str
    odom_frame: str = None  # None: gz's <model>/odom
    robot_base_frame: str = None  # None: gz's <model>/base_footprint
    odom_publish_frequency: float = 50.0  # Hz; 0 or less: every step
    odom_topic: str = None  # valid gz topics the block gives; None: gz's defaults
    odom_covariance_topic: str = None
    tf_topic: str = None
    dimensions: int = 2
    xyz_offset: tuple = (0.0, 0.0, 0.0)
    rpy_offset: tuple = (0.0, 0.0, 0.0)
    gaussian_noise: float = 0.0  # standard deviation of each twist component
    notes: tuple = ()


def read_config(block, robot):
    """Return the GzOdometryConfig of an OdometryPublisher block, or refuse it."""
    parameters = GzParameters(block, 'OdometryPublisher')
    dimensions = parameters.number('dimensions', 2, minimum=2, maximum=3)
    if dimensions not in (2, 3):
        raise UrdfError(f'OdometryPublisher <dimensions> must be 2 or 3: {dimensions:g}')
    offset = parameters.vector('xyz_offset', (0.0, 0.0, 0.0))
    if max(abs(value) for value in offset) > MAX_SIZE:
        raise UrdfError(f'OdometryPublisher <xyz_offset> must stay within {MAX_SIZE:g} m: '
                        f'{list(offset)}')
    return GzOdometryConfig(
        robot_name=robot.name, odom_frame=parameters.frame('odom_frame'),
        robot_base_frame=parameters.frame('robot_base_frame'),
        odom_publish_frequency=parameters.rate('odom_publish_frequency', 50.0),
        odom_topic=parameters.topic('odom_topic'),
        odom_covariance_topic=parameters.topic('odom_covariance_topic'),
        tf_topic=parameters.topic('tf_topic'), dimensions=int(dimensions), xyz_offset=offset,
        rpy_offset=parameters.vector('rpy_offset', (0.0, 0.0, 0.0)),
        gaussian_noise=parameters.number('gaussian_noise', 0.0, minimum=0.0,
                                         maximum=MAX_NOISE),
        notes=tuple(parameters.notes))


class GzOdometryPublisher(Plugin):
    """A model's ground-truth odometry, handed to its listener at gz's rate."""

    title = 'OdometryPublisher system'
    is_gz_system = True

    def __init__(self, config, block):
        """Start with no listener and nothing due."""
        super().__init__(config, block)
        self.listener = None
        self.odometry_frame = self.base_frame = ''
        self._next_odometry = math.inf
        self._root = 0
        self._offset = (np.array(config.xyz_offset), frames.rpy_quaternion(config.rpy_offset))

    @classmethod
    def configure(cls, block, robot):
        """Return the GzOdometryConfig of the block (see read_config)."""
        return read_config(block, robot)

    @functools.cached_property
    def random(self):
        """Return the noise generator, seeded by the model's name: the same noise each run."""
        return np.random.default_rng(zlib.crc32(self.config.robot_name.encode()))

    def gz_topics(self, model_name):
        """Return the publisher's gz topics for a model of that name, by role."""
        config = self.config
        return {
            'odometry': gz_names.first_valid_topic(
                config.odom_topic, gz_names.model_topic(model_name, 'odometry')),
            'odometry_with_covariance': gz_names.first_valid_topic(
                config.odom_covariance_topic,
                gz_names.model_topic(model_name, 'odometry_with_covariance')),
            'tf': gz_names.first_valid_topic(
                config.tf_topic, gz_names.model_topic(model_name, 'pose'))}

    def bind(self, world, model):
        """Find the model's root link and name its frames."""
        super().bind(world, model)
        self._root = model.root_id
        self.odometry_frame = self.config.odom_frame or gz_names.model_frame(model.name, 'odom')
        self.base_frame = self.config.robot_base_frame or gz_names.model_frame(
            model.name, 'base_footprint')

    @property
    def odometry_period(self):
        """Return the simulation time between two updates: at least one step."""
        frequency = self.config.odom_publish_frequency
        return max(self.world.timestep, 1.0 / frequency if frequency > 0.0 else 0.0)

    def next_event(self):
        """Return when odometry is next due."""
        return self._next_odometry

    def update(self, now):
        """Hand the odometry to the listener, and schedule the next."""
        self._next_odometry += self.odometry_period
        if self._next_odometry <= now:  # late, after a reset of time: go on from now
            self._next_odometry = self.world.time + self.odometry_period
        if self.listener is not None:
            self.listener(self)

    def reset(self):
        """Start again one period from now."""
        self._next_odometry = self.world.time + self.odometry_period

    def odometry(self):
        """Return the model's pose in the world and its twist in its own frame, with noise."""
        base = self.world.body_state(self._root)
        position, orientation = frames.compose(base.position, base.orientation, *self._offset)
        if self.config.dimensions == 2:
            position = np.array([position[0], position[1], 0.0])
        linear = frames.rotate_back(base.orientation, base.linear_velocity)
        angular = frames.rotate_back(base.orientation, base.angular_velocity)
        noise = self.config.gaussian_noise
        if noise > 0.0:
            linear = linear + self.random.normal(0.0, noise, 3)
            angular = angular + self.random.normal(0.0, noise, 3)
        return Odometry(position=np.asarray(position), orientation=np.asarray(orientation),
                        linear_velocity=linear, angular_velocity=angular,
                        odometry_frame=self.odometry_frame, robot_base_frame=self.base_frame)

    @property
    def covariance(self):
        """Return the variance of each twist component, on the covariances' diagonals."""
        return self.config.gaussian_noise ** 2


PLUGIN = GzOdometryPublisher
