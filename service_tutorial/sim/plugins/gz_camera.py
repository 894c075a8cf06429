"""
gz-sim's cameras (<sensor type="camera">, "depth_camera", "rgbd_camera"), simulation side.

The Classic camera (camera_sensor.py) draws each frame, with the world's renderer; a depth
camera reads the depth buffer of the same drawing, as distances along the optical axis in m
(32FC1, +inf where nothing is within <clip><far>), with the gaussian <noise> of its <camera>
added, and its points are those distances put back through the pinhole, in the sensor frame
(x forward, y left, z up). A colour image's <noise> is added to each channel, as a fraction of
its full range. Topics, as gz-sensors names them from the sensor's <topic> T (else gz's default
below the sensor): a camera's image on T (default .../image), its camera_info on
<camera_info_topic>, else beside T; a depth camera's depth image on T (.../depth_image), its
points on T/points, its camera_info beside T; an RGBD camera's T/image, T/depth_image,
T/points and T/camera_info (T: the sensor's own default). <optical_frame_id> relabels the
frame of the images, as gz does, without turning it.
"""

from dataclasses import dataclass

import numpy as np
from service_tutorial.sim.plugins.camera_sensor import camera_fields, CameraConfig
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.plugins.gz_names import valid_topic
from service_tutorial.sim.plugins.gz_sensor import gz_sensor_fields, GzSensor, parent_topic
from service_tutorial.sim.plugins.sensor import gaussian_noise, sensor_of

# <sensor type> (with sdformat's aliases) -> (draws colour, reads depth).
CAMERA_TYPES = {'camera': (True, False), 'depth_camera': (False, True), 'depth': (False, True),
                'rgbd_camera': (True, True), 'rgbd': (True, True)}
DEPTH_ENCODING = '32FC1'


@dataclass(frozen=True)
class GzCameraConfig(CameraConfig):
    """A gz camera: colour, depth or both, its noise and its topics."""

    colour: bool = True
    depth: bool = False
    noise_mean: float = 0.0  # m for a depth image, a fraction of full range for colour
    noise_stddev: float = 0.0
    camera_info_topic: str = None
    optical_frame_id: str = None
    robot_name: str = ''  # the model's own name, for its gz topics until it is spawned
    topic: str = None
    gz_frame_id: str = None
    always_on: bool = True
    notes: tuple = ()


def read_config(block, robot):
    """Return the GzCameraConfig of a gz camera's <sensor>, or refuse what is absurd."""
    sensor = sensor_of(block, tuple(CAMERA_TYPES), 'camera')
    colour, depth = CAMERA_TYPES[sensor.sensor_type]
    fields = camera_fields(sensor, encoding=None if colour else DEPTH_ENCODING)
    mean, stddev = gaussian_noise(sensor, 'camera/noise')
    info_topic = sensor.text('camera/camera_info_topic')
    gz_fields = gz_sensor_fields(sensor, robot)
    return GzCameraConfig(
        **fields, colour=colour, depth=depth, noise_mean=mean, noise_stddev=stddev,
        camera_info_topic=valid_topic(info_topic) if info_topic else None,
        optical_frame_id=sensor.text('camera/optical_frame_id') or None, **gz_fields)


class GzCamera(GzSensor, CameraSensor):
    """A gz camera on a robot's link: an image, a depth image (float32, m), or both."""

    title = 'camera'

    def __init__(self, config, block):
        """Start with no image and no depth."""
        super().__init__(config, block)
        self.depth = None

    @classmethod
    def configure(cls, block, robot):
        """Return the GzCameraConfig of the block's <sensor> (see read_config)."""
        return read_config(block, robot)

    def gz_topics(self, model_name, world_name):
        """Return the camera's gz topics by role: image, depth_image, points, camera_info."""
        config = self.config
        if config.colour and config.depth:
            base = self.gz_topic(model_name, world_name)
            return {'image': base + '/image', 'depth_image': base + '/depth_image',
                    'points': base + '/points', 'camera_info': base + '/camera_info'}
        if config.depth:
            depth = self.gz_topic(model_name, world_name, 'depth_image')
            return {'image': None, 'depth_image': depth, 'points': depth + '/points',
                    'camera_info': parent_topic(depth) + '/camera_info'}
        image = self.gz_topic(model_name, world_name, 'image')
        return {'image': image, 'depth_image': None, 'points': None,
                'camera_info': config.camera_info_topic or parent_topic(image) + '/camera_info'}

    def gz_frame(self, model_name):
        """Return the frame of the images: <optical_frame_id>, else the sensor's."""
        return self.config.optical_frame_id or super().gz_frame(model_name)

    def _drawn(self, drawing=None):
        """Draw the last snapshot: the image, or (image or None, depth) for a depth camera."""
        config = self.config
        if not config.depth:
            return self._noisy_image(super()._drawn(drawing))
        image, depth = self._view.render_snapshot(drawing, depth=True)
        image = self._noisy_image(self._encoded(image)) if config.colour else None
        if config.noise_stddev > 0.0 or config.noise_mean != 0.0:
            depth += self.random.normal(config.noise_mean, config.noise_stddev,
                                        depth.shape).astype(np.float32)
        return image, depth

    def _noisy_image(self, image):
        config = self.config
        if config.noise_stddev <= 0.0 and config.noise_mean == 0.0:
            return image
        noise = self.random.normal(config.noise_mean * 255.0, config.noise_stddev * 255.0,
                                   image.shape)
        return np.clip(np.round(image + noise), 0, 255).astype(np.uint8)

    def frame_rendered(self, pixels, taken_at):
        """Take a frame drawn in the background (with its depth) as a reading."""
        if self.config.depth:
            pixels, self.depth = pixels
        super().frame_rendered(pixels, taken_at)

    def read(self):
        """Render the world from the camera: its image, its depth or both."""
        self._snapshot()
        drawn = self._drawn()
        if self.config.depth:
            self.image, self.depth = drawn
        else:
            self.image = drawn

    def points(self):
        """Return the last depth image's points, (height, width, 3) float32 in the sensor frame."""
        k = self.config.intrinsic_matrix()
        height, width = self.depth.shape
        columns, rows = np.meshgrid(np.arange(width), np.arange(height))
        forward = self.depth
        with np.errstate(invalid='ignore'):
            left = -(columns - k[0, 2]) / k[0, 0] * forward
            up = -(rows - k[1, 2]) / k[1, 1] * forward
        points = np.stack([forward, left, up], axis=-1).astype(np.float32)
        points[~np.isfinite(forward)] = np.inf
        return points


PLUGIN = GzCamera
