"""
The world node's camera: an image topic, its camera_info, and snapshots written on request.

The node calls publish_due() from its publish step. With camera_enabled false no image
publisher exists and publish_due() returns at once. With it true, frames fall due at
camera_rate, in Hz of simulation time like the node's other rates, but only while someone
subscribes: without subscribers next_due stays infinite, so the stepping loop never stops for
the camera, and publish_due() looks for a subscriber a few times per wall second. The renderer
and its GL context are made on first use.
"""

import math
import os
import time

from sensor_msgs.msg import CameraInfo, Image
from service_tutorial.conversions import time_msg
from service_tutorial.image_files import write_png
from service_tutorial.sim.rendering import SceneCamera
from std_srvs.srv import Trigger

CAMERA_FRAME = 'camera_optical_frame'  # z forward, x right, y down (REP 103, optical frames)
SUBSCRIBER_CHECK_PERIOD = 0.2  # s of wall time between two looks for a first subscriber


class CameraStream:
    """Renders the world for ~/camera/image_raw and ~/camera/camera_info, and snapshots."""

    def __init__(self, node, world, parameters):
        """Make the camera from the node's camera_* parameters (a dict of values)."""
        self.node = node
        self.world = world
        self.enabled = bool(parameters['camera_enabled'])
        rate = float(parameters['camera_rate'])
        if self.enabled and not rate > 0.0:
            raise ValueError(f'camera_rate must be above 0 Hz, got {rate}')
        self.period = 1.0 / rate if self.enabled else math.inf
        self.camera = SceneCamera(
            parameters['camera_width'], parameters['camera_height'],
            list(parameters['camera_position']), list(parameters['camera_look_at']),
            parameters['camera_fovy'])
        self.snapshot_directory = parameters['snapshot_directory'] or os.getcwd()
        self.next_due = math.inf  # simulation time of the next frame; inf: nobody listens
        self._next_subscriber_check = 0.0
        self.image_pub = self.info_pub = None
        if self.enabled:
            self.image_pub = node.create_publisher(Image, '~/camera/image_raw', 2)
            self.info_pub = node.create_publisher(CameraInfo, '~/camera/camera_info', 2)
        self.snapshot_srv = node.create_service(
            Trigger, '~/save_snapshot', self.save_snapshot_callback)

    def publish_due(self, now):
        """Publish a frame and its camera_info if one is due and anyone listens."""
        if not self.enabled:
            return
        if self.next_due == math.inf:
            wall = time.monotonic()
            if wall < self._next_subscriber_check:
                return
            self._next_subscriber_check = wall + SUBSCRIBER_CHECK_PERIOD
            if not self._listened_to():
                return
            self.next_due = now  # a first subscriber: the first frame is due now
        # Half a step of slack: simulation time is a sum of steps and carries rounding errors.
        soon = now + 0.5 * self.world.timestep
        if soon < self.next_due:
            if now + self.period >= self.next_due:
                return
            # Simulation time went back (reset_simulation): the next frame is due now.
        self.next_due = now + self.period
        if not self._listened_to():
            self.next_due = math.inf
            return
        if self.info_pub.get_subscription_count() > 0:
            self.info_pub.publish(self.camera_info(now))
        if self.image_pub.get_subscription_count() > 0:
            self.image_pub.publish(self.image(now))

    def _listened_to(self):
        """Tell whether anyone subscribes to the image or to the camera_info."""
        return self.image_pub.get_subscription_count() > 0 or \
            self.info_pub.get_subscription_count() > 0

    def image(self, now):
        """Render the world as a sensor_msgs/Image (rgb8) stamped with simulation time."""
        pixels = self.camera.render(self.world.model, self.world.data)
        msg = Image()
        msg.header.stamp = time_msg(now)
        msg.header.frame_id = CAMERA_FRAME
        msg.height, msg.width = pixels.shape[:2]
        msg.encoding = 'rgb8'
        msg.is_bigendian = 0
        msg.step = 3 * msg.width
        msg.data = pixels.tobytes()
        return msg

    def camera_info(self, now):
        """Describe the pinhole camera: no distortion, square pixels, K from fovy and size."""
        msg = CameraInfo()
        msg.header.stamp = time_msg(now)
        msg.header.frame_id = CAMERA_FRAME
        msg.height, msg.width = self.camera.height, self.camera.width
        msg.distortion_model = 'plumb_bob'
        msg.d = [0.0] * 5
        k = self.camera.intrinsic_matrix()
        msg.k = [float(v) for v in k.reshape(-1)]
        msg.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
        msg.p = [float(k[0, 0]), 0.0, float(k[0, 2]), 0.0,
                 0.0, float(k[1, 1]), float(k[1, 2]), 0.0,
                 0.0, 0.0, 1.0, 0.0]
        return msg

    def save_snapshot_callback(self, request, response):
        """Render the world now and write it as a PNG into snapshot_directory."""
        now = self.world.time
        path = os.path.join(self.snapshot_directory, f'snapshot_t{now:010.3f}.png')
        try:
            os.makedirs(self.snapshot_directory, exist_ok=True)
            write_png(path, self.camera.render(self.world.model, self.world.data))
        except Exception as error:  # no GL, a full disk: an answer, never a crashed world
            response.success = False
            response.message = f'could not save a snapshot to {path}: {error}'
            self.node.get_logger().error(response.message)
            return response
        response.success = True
        response.message = os.path.abspath(path)
        self.node.get_logger().info(f'snapshot of t={now:.3f} s written to {response.message}')
        return response

    def close(self):
        """Release the renderer and its GL context."""
        self.camera.close()
