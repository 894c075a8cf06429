"""
The world node's camera: an image topic, its camera_info, and snapshots written on request.

The node calls publish_due() from its publish step. With camera_enabled false no image
publisher exists and publish_due() returns at once. With it true, frames fall due at
camera_rate, in Hz of simulation time like the node's other rates, but only while someone
subscribes: without subscribers next_due stays infinite, so the stepping loop never stops for
the camera, and publish_due() looks for a subscriber a few times per wall second. The renderer
and its GL context are made on first use.

configure() takes the node's camera parameters at start-up and whichever of them are set at
run time: enabling or disabling makes or removes the topics, a new rate moves the next frame,
a new size, pose or field of view makes a new camera (its renderer again made on first use).
"""

import math
import os

import PIL.Image
from sensor_msgs.msg import CameraInfo, Image
from service_tutorial.conversions import pixel_bytes, time_msg
from service_tutorial.sim.rendering import SceneCamera
from service_tutorial.world_node.subscribers import SubscriberWatch
from std_srvs.srv import Trigger

CAMERA_FRAME = 'camera_optical_frame'  # z forward, x right, y down (REP 103, optical frames)
# The world parameters the camera follows, and those of them that make a new camera.
VIEW_PARAMETERS = ('camera_width', 'camera_height', 'camera_position', 'camera_look_at',
                   'camera_fovy')
CAMERA_PARAMETERS = ('camera_enabled', 'camera_rate', *VIEW_PARAMETERS, 'snapshot_directory')


class CameraStream:
    """Renders the world for ~/camera/image_raw and ~/camera/camera_info, and snapshots."""

    def __init__(self, node, world, parameters):
        """Make the camera from the node's camera parameters (a mapping of their values)."""
        self.node = node
        self.world = world
        self.enabled = False
        self.rate = parameters['camera_rate']
        self.period = math.inf  # s of simulation time between frames; inf: disabled
        self.view = {}  # the camera's VIEW_PARAMETERS, by name
        self.camera = None
        self.snapshot_directory = os.getcwd()
        self.next_due = math.inf  # simulation time of the next frame; inf: nobody listens
        self.image_pub = self.info_pub = None
        self._watch = None  # SubscriberWatch of both topics while enabled
        self.snapshot_srv = node.serve(
            Trigger, '~/save_snapshot', self.save_snapshot_callback)
        self.configure(parameters)

    def configure(self, settings):
        """Apply some or all of CAMERA_PARAMETERS (a mapping of their values), at once."""
        view = {name: settings[name] for name in VIEW_PARAMETERS if name in settings}
        if view:
            view = {**self.view, **view}
            camera = SceneCamera(view['camera_width'], view['camera_height'],
                                 list(view['camera_position']), list(view['camera_look_at']),
                                 view['camera_fovy'])
            if self.camera is not None:
                self.camera.close()
            self.camera, self.view = camera, view
        if 'snapshot_directory' in settings:
            self.snapshot_directory = settings['snapshot_directory'] or os.getcwd()
        if 'camera_rate' in settings:
            self.rate = settings['camera_rate']
        enabled = settings.get('camera_enabled', self.enabled)
        if enabled and not self.enabled:
            self.image_pub = self.node.create_publisher(Image, '~/camera/image_raw', 2)
            self.info_pub = self.node.create_publisher(CameraInfo, '~/camera/camera_info', 2)
            self._watch = SubscriberWatch(self.image_pub, self.info_pub)
        elif self.enabled and not enabled:
            self.node.destroy_publisher(self.image_pub)
            self.node.destroy_publisher(self.info_pub)
            self.image_pub = self.info_pub = self._watch = None
            self.next_due = math.inf
        self.enabled = enabled
        period = 1.0 / self.rate if enabled else math.inf
        if self.next_due < math.inf:
            # The next frame comes one new period after the last one.
            self.next_due += period - self.period
        self.period = period

    def publish_due(self, now):
        """Publish a frame and its camera_info if one is due and anyone listens."""
        if not self.enabled:
            return
        if self.next_due == math.inf:
            if not self._watch.listened():
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
        msg.data = pixel_bytes(pixels)
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
            PIL.Image.fromarray(self.camera.render(self.world.model, self.world.data)).save(
                path, format='PNG')
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
        if self.camera is not None:
            self.camera.close()
