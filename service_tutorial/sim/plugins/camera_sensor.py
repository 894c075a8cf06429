"""
The Gazebo camera plugin (gazebo_ros_camera, ROS 1 and ROS 2), simulation side.

A <sensor type="camera"> becomes a MuJoCo camera on the link, rendered offscreen by the same
renderer as the world's scene camera (rendering.py), with the block's image size, horizontal
field of view and clipping distances; in a world that renders in the background
(background_renders.py), each frame is drawn on the rendering thread and handed on once drawn.
Gazebo's camera looks along the x axis of its link with z up; MuJoCo's looks along -z with y
up, hence the fixed turn OPTICAL_TURN between the two.
"""

from dataclasses import dataclass
import math

import mujoco
import numpy as np
from service_tutorial.sim.core_logs import core_logger
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.sensor import Sensor
from service_tutorial.sim.plugins.sensor import sensor_of
from service_tutorial.sim.plugins.sensor import SENSOR_SITE_GROUP
from service_tutorial.sim.plugins.sensor import SensorConfig
from service_tutorial.sim.rendering import OffscreenCamera
from service_tutorial.sim.rendering import pinhole_matrix
from service_tutorial.sim.validation import quoted

_logger = core_logger(__name__)

# From a Gazebo camera's frame (x forward, z up) to MuJoCo's (-z forward, y up), (w, x, y, z).
OPTICAL_TURN = (0.5, 0.5, -0.5, -0.5)
# The largest image a camera may ask for, in pixels along either side and in all. Drawn on the
# rendering thread, a frame costs the world its copy and its message: with a 4096x4096 camera
# listened to, answers took up to 0.8 s; with 2048x2048, under 0.1 s.
MAX_IMAGE_SIDE = 4096
MAX_IMAGE_PIXELS = 2048 * 2048
# SDF image formats -> sensor_msgs/Image encodings.
ENCODINGS = {'R8G8B8': 'rgb8', 'RGB_INT8': 'rgb8', 'B8G8R8': 'bgr8', 'BGR_INT8': 'bgr8',
             'L8': 'mono8', 'L_INT8': 'mono8'}
# ITU-R BT.601 luma, for mono8 images.
_LUMA = np.array([0.299, 0.587, 0.114])


@dataclass(frozen=True)
class CameraConfig(SensorConfig):
    """A camera's image: its size, horizontal field of view, clipping and encoding."""

    width: int  # pixels
    height: int  # pixels
    horizontal_fov: float  # rad
    near: float  # m, nearest distance drawn
    far: float  # m, farthest distance drawn
    encoding: str  # sensor_msgs/Image encoding: rgb8, bgr8 or mono8

    @property
    def fovy(self):
        """Return the vertical field of view in degrees, for square pixels."""
        return math.degrees(
            2.0 * math.atan(math.tan(self.horizontal_fov / 2.0) * self.height / self.width))

    def intrinsic_matrix(self):
        """Return the 3x3 pinhole matrix K; its fx follows from the horizontal field of view."""
        return pinhole_matrix(self.width, self.height, self.fovy)


def read_config(block):
    """Return the CameraConfig of a camera plugin from the <sensor> it sits in."""
    return CameraConfig(**camera_fields(sensor_of(block, ('camera',), 'camera')))


def camera_fields(sensor, *, encoding=None):
    """
    Return the CameraConfig fields of a <sensor>'s <camera>, or refuse what is absurd.

    encoding: the image's, for a camera whose <image/format> is not read (a depth camera's).
    """
    size = {}
    for side, default in (('width', 320), ('height', 240)):
        size[side] = sensor.number(f'camera/image/{side}', default, above=0, whole=True)
        if size[side] > MAX_IMAGE_SIDE:
            raise UrdfError(f'sensor {quoted(sensor.name)} <camera/image/{side}> must be at '
                            f'most {MAX_IMAGE_SIDE}: {size[side]}')
    if size['width'] * size['height'] > MAX_IMAGE_PIXELS:
        raise UrdfError(f'sensor {quoted(sensor.name)} <camera/image> of {size["width"]}x'
                        f'{size["height"]} has {size["width"] * size["height"]} pixels, more '
                        f'than {MAX_IMAGE_PIXELS} (2048x2048)')
    horizontal_fov = sensor.number('camera/horizontal_fov', 1.047, above=0.0)
    if horizontal_fov >= math.pi:
        raise UrdfError(f'sensor {quoted(sensor.name)} <camera/horizontal_fov> must be below '
                        f'pi for a pinhole camera: {horizontal_fov:g}')
    near = sensor.number('camera/clip/near', 0.1, above=0.0)
    far = sensor.number('camera/clip/far', 100.0, above=near)
    if encoding is None:
        image_format = sensor.text('camera/image/format', 'R8G8B8')
        if image_format not in ENCODINGS:
            raise UrdfError(f'sensor {quoted(sensor.name)} <camera/image/format> must be one of '
                            f'{", ".join(ENCODINGS)}: {quoted(image_format)}')
        encoding = ENCODINGS[image_format]
    return {'name': sensor.name, 'link': sensor.link, 'position': sensor.position,
            'orientation': sensor.orientation, 'update_rate': sensor.update_rate,
            'width': size['width'], 'height': size['height'],
            'horizontal_fov': horizontal_fov, 'near': near, 'far': far, 'encoding': encoding}


class CameraSensor(Sensor):
    """A camera on a robot's link: each reading is an image, (height, width, 3) or mono."""

    title = 'camera'
    kind = 'camera'

    def __init__(self, config, block):
        """Start with no image; the renderer is made on the first reading."""
        super().__init__(config, block)
        self.image = None
        self._view = OffscreenCamera(config.width, config.height)
        self._camera_id = -1
        self._fell_behind = False  # said once in the log

    @classmethod
    def configure(cls, block, robot):
        """Return the CameraConfig of the block's <sensor> (see read_config)."""
        return read_config(block)

    @classmethod
    def build(cls, spec, config, timestep):
        """Put a MuJoCo camera, and a site, at the sensor's pose on its link."""
        body = spec.body(config.link)
        name = config.site_name(cls.kind)
        body.add_site(name=name, pos=config.position, quat=config.orientation,
                      group=SENSOR_SITE_GROUP)
        quaternion = np.zeros(4)
        mujoco.mju_mulQuat(quaternion, np.array(config.orientation), np.array(OPTICAL_TURN))
        body.add_camera(name=name, pos=config.position, quat=quaternion, fovy=config.fovy)

    def bind(self, world, model):
        """Find the camera in the compiled model."""
        super().bind(world, model)
        self._camera_id = model.element_id(world.model, mujoco.mjtObj.mjOBJ_CAMERA,
                                           self.config.site_name(self.kind))

    def update(self, now):
        """Take a reading; in the background, skip it while the last frame is being drawn."""
        renders = self.world.background_renders
        if renders is None:
            super().update(now)
            return
        if renders.busy(self):
            if not self._fell_behind:
                self._fell_behind = True
                _logger.warning(
                    "camera %s of model '%s' takes longer to render than its period of %.3g s: "
                    'frames are skipped until it catches up', quoted(self.config.name),
                    self.model.name, self.period)
        else:
            self._snapshot()
            renders.submit(self, self._drawn, self.world.time)
        self.schedule_next(now)

    def frame_rendered(self, pixels, taken_at):
        """Take a frame drawn in the background as the reading of simulation time taken_at."""
        if not self.active:  # nobody listens any more
            return
        self.image = pixels
        self.reading_time = taken_at
        if self.listener is not None:
            self.listener(self)

    def read(self):
        """Render the world from the camera, in the block's encoding."""
        self._snapshot()
        self.image = self._drawn()

    def _snapshot(self):
        config = self.config
        self._view.take_snapshot(self.world.model, self.world.data, self._camera_id,
                                 config.fovy, config.near, config.far)

    def _drawn(self, drawing=None):
        """Draw the last snapshot in the block's encoding (with the camera's own Drawing)."""
        return self._encoded(self._view.render_snapshot(drawing))

    def _encoded(self, pixels):
        """Return rendered RGB pixels in the block's encoding."""
        encoding = self.config.encoding
        if encoding == 'bgr8':
            pixels = np.ascontiguousarray(pixels[:, :, ::-1])
        elif encoding == 'mono8':
            pixels = np.round(pixels @ _LUMA).astype(np.uint8)
        return pixels

    def close(self):
        """Release the renderer and its GL context, once a frame being drawn is done."""
        if self.world is not None and self.world.background_renders is not None:
            self.world.background_renders.forget(self)
        self._view.close()


PLUGIN = CameraSensor
