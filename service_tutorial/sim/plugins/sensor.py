"""
What the sensor plugins share: a place on a link, a rate, being listened to, and noise.

A sensor measures only while it is active (its ROS face makes it so while its topic has a
subscriber), at its update rate in simulation time: its next_event() is the time of the next
reading, or infinity while nobody listens, so an idle sensor never stops the stepping and
costs nothing. Each reading goes to the sensor's listener, a plain callable (the ROS face).
Readings see the world as MuJoCo's own sensors do: as it was at the start of the last step.
"""

from dataclasses import dataclass
import functools
import math
import zlib

import mujoco
import numpy as np
from service_tutorial.sim.description import frame_id
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.validation import quoted

# Sites of sensors go in a geom group that the renderer does not draw (it draws 0 to 2).
SENSOR_SITE_GROUP = 5
# The tags that name the frame of a sensor's messages: ROS 1's and ROS 2's gazebo_ros.
FRAME_TAGS = ('frameName', 'frame_name')


@dataclass(frozen=True)
class SensorConfig:
    """Where a sensor sits and how often it measures."""

    name: str  # the <sensor name>, or the plugin's name for a ROS 1 model plugin
    link: str  # the URDF link it is fixed to
    position: tuple  # (x, y, z) in the link's frame
    orientation: tuple  # (w, x, y, z) in the link's frame
    update_rate: float  # Hz of simulation time; 0: every physics step

    def site_name(self, kind):
        """Return the name of the MuJoCo site that marks the sensor on its link."""
        return f'{kind}:{self.name}'


def sensor_of(block, types, title):
    """Return the SensorBlock a sensor plugin sits in, or refuse one that sits elsewhere."""
    sensor = block.sensor
    where = f'plugin {quoted(block.name)} ({block.filename})'
    wanted = ' or '.join(f'<sensor type="{kind}">' for kind in types)
    if sensor is None:
        raise UrdfError(f'{where} is a {title} plugin: it belongs in a {wanted} of a '
                        '<gazebo reference="link"> block')
    if sensor.sensor_type not in types:
        raise UrdfError(f'{where} needs a {wanted}, but sits in sensor {quoted(sensor.name)} '
                        f'of type {quoted(sensor.sensor_type)}')
    if not sensor.name:
        raise UrdfError(f'the <sensor type="{sensor.sensor_type}"> on link {quoted(sensor.link)} '
                        'has no name')
    check_frame_names(block)
    return sensor


def check_frame_names(block):
    """Refuse a sensor plugin whose frameName or frame_name tf2 could not take (frame_id)."""
    for tag in FRAME_TAGS:
        text = block.text(tag)
        if text:  # an empty one means the sensor's link, as if it were not there
            frame_id(text, f'plugin {quoted(block.name)} <{tag}>')


def gaussian_noise(sensor, path):
    """Return (mean, stddev) of a <noise> element below <sensor>; (0, 0) without one."""
    kind = sensor.text(f'{path}/type', 'none' if sensor.text(f'{path}/stddev') is None
                       else 'gaussian')
    if kind.lower() == 'none':
        return 0.0, 0.0
    if kind.lower() not in ('gaussian', 'gaussian_quantized'):
        raise UrdfError(f'sensor {quoted(sensor.name)} <{path}/type> must be gaussian or '
                        f'none: {quoted(kind)}')
    return (sensor.number(f'{path}/mean', 0.0),
            sensor.number(f'{path}/stddev', 0.0, minimum=0.0))


class Sensor(Plugin):
    """A sensor plugin: reads at its rate while active, and hands each reading on."""

    single = False
    title = 'sensor'
    kind = 'sensor'  # names the sensor's site: '<kind>:<name>'

    def __init__(self, config, block):
        """Start inactive, with no reading."""
        super().__init__(config, block)
        self.active = False
        self.listener = None  # called with the sensor after each reading
        self.reading_time = None  # simulation time of the latest reading
        self._next_reading = math.inf
        self.site_id = -1

    @functools.cached_property
    def random(self):
        """Return the noise generator, seeded by the sensor's name: the same noise each run."""
        # Made when first drawn from: making one costs more than a warm spawn's bookkeeping.
        return np.random.default_rng(zlib.crc32(self.config.name.encode()))

    @property
    def period(self):
        """Return the simulation time between two readings, at least one physics step."""
        rate = self.config.update_rate
        return max(self.world.timestep, 1.0 / rate if rate > 0.0 else 0.0)

    def bind(self, world, model):
        """Find the sensor's site in the compiled model."""
        super().bind(world, model)
        self.site_id = model.element_id(world.model, mujoco.mjtObj.mjOBJ_SITE,
                                        self.config.site_name(self.kind))

    def set_active(self, active):
        """Start measuring (from the next step on) or stop, as the sensor is listened to."""
        active = bool(active)
        if active == self.active:
            return
        self.active = active
        # The first reading comes with the next step; later ones a whole period after it.
        self._next_reading = self._next_step() if active else math.inf
        self.world.schedule_event(self._next_reading)

    def next_event(self):
        """Return when the next reading is due; never while inactive."""
        return self._next_reading

    def update(self, now):
        """Take a reading, schedule the next one at the sensor's rate, tell the listener."""
        self.read()
        self.reading_time = self.world.time
        self.schedule_next(now)
        if self.listener is not None:
            self.listener(self)

    def schedule_next(self, now):
        """Schedule the next reading one period after the one due by simulation time now."""
        period = self.period
        self._next_reading += period
        if self._next_reading <= now:  # late, after a pause in activity: go on from now
            self._next_reading = self.world.time + period

    def read(self):
        """Measure the world now and keep the result (each kind of sensor says how)."""
        raise NotImplementedError

    def reset(self):
        """After a reset, an active sensor measures again from the next step on."""
        if self.active:
            self._next_reading = self._next_step()

    def _next_step(self):
        return self.world.time + self.world.timestep
