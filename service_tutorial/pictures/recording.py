"""
Record what the world's camera sees and where tinybot goes, then save a GIF and an SVG plot.

TurnRecorder keeps camera frames at a steady rate of simulation time (by their stamps, not by
when they arrive) and every odometry sample. When the frames reach their cap it drops every
second one and halves its rate, so a long recording still covers the whole run in bounded
memory and the GIF still plays at the speed of the simulation.
"""

import math
import os
import time

from nav_msgs.msg import Odometry
import numpy as np
from sensor_msgs.msg import Image
from service_tutorial.conversions import seconds_of, yaw_of
from service_tutorial.pictures.image_files import write_animation
from service_tutorial.pictures.trajectory_plot import write_trajectory_plot

ANIMATION_FILE = 'turning.gif'
TRAJECTORY_FILE = 'trajectory.svg'
CAMERA_IMAGE_TOPIC = '/mujoco/camera/image_raw'
MAX_ODOMETRY_SAMPLES = 200_000  # over an hour of odometry at 50 Hz


def image_pixels(msg):
    """Unpack an rgb8 or bgr8 sensor_msgs/Image into an (H, W, 3) RGB array."""
    if msg.encoding not in ('rgb8', 'bgr8'):
        raise ValueError(f'cannot record images of encoding {msg.encoding!r}: '
                         'only rgb8 and bgr8')
    rows = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)
    pixels = rows[:, :3 * msg.width].reshape(msg.height, msg.width, 3)
    if msg.encoding == 'bgr8':
        pixels = pixels[:, :, ::-1]
    return np.ascontiguousarray(pixels)


class TurnRecorder:
    """Collects camera frames and odometry from a node's subscriptions until save()."""

    def __init__(self, node, *, image_topic=CAMERA_IMAGE_TOPIC, odom_topic='/odom', fps=10.0,
                 max_frames=400):
        if not fps > 0.0:
            raise ValueError(f'fps must be above 0, got {fps}')
        if max_frames < 2:
            raise ValueError(f'max_frames must be at least 2, got {max_frames}')
        self.node = node
        self.frame_period = 1.0 / fps
        self.max_frames = int(max_frames)
        self.frames = []
        self.odometry = []  # (time, x, y, yaw)
        self._next_frame_time = -math.inf
        self.image_sub = node.create_subscription(Image, image_topic, self.image_callback, 5)
        self.odom_sub = node.create_subscription(Odometry, odom_topic, self.odom_callback, 50)

    @property
    def fps(self):
        """Frames per second of simulation time of the frames kept."""
        return 1.0 / self.frame_period

    def image_callback(self, msg):
        """Keep a frame if its stamp is one frame period after the last one kept."""
        stamp = seconds_of(msg.header.stamp)
        wait = self._next_frame_time - stamp
        if wait > self.frame_period + 1e-6:
            wait = -math.inf  # the clock went back (a reset): start afresh from this frame
        if wait > 1e-6:
            return
        # Keep to the schedule, unless frames stopped coming for longer than a period.
        start = self._next_frame_time if wait > -self.frame_period else stamp
        self._next_frame_time = start + self.frame_period
        self.frames.append(image_pixels(msg))
        if len(self.frames) >= self.max_frames:
            self.frames = self.frames[::2]
            self.frame_period *= 2.0

    def odom_callback(self, msg):
        """Keep the time, position and heading of an odometry message."""
        if len(self.odometry) >= MAX_ODOMETRY_SAMPLES:
            return
        pose = msg.pose.pose
        self.odometry.append((seconds_of(msg.header.stamp), pose.position.x, pose.position.y,
                              yaw_of(pose.orientation)))

    def wait_for_frame(self, timeout):
        """Wait until a first frame is kept, while another thread spins; return if it was."""
        deadline = time.monotonic() + timeout
        while not self.frames and time.monotonic() < deadline:
            time.sleep(0.05)
        return bool(self.frames)

    def stop(self):
        """Stop listening; what was recorded stays."""
        if self.image_sub is not None:
            self.node.destroy_subscription(self.image_sub)
            self.node.destroy_subscription(self.odom_sub)
            self.image_sub = self.odom_sub = None

    def save(self, directory):
        """Stop, write turning.gif and trajectory.svg into directory, return their paths."""
        self.stop()
        os.makedirs(directory, exist_ok=True)
        paths = []
        if self.frames:
            paths.append(write_animation(os.path.join(directory, ANIMATION_FILE),
                                         self.frames, self.fps))
        if self.odometry:
            times, x, y, yaw = np.array(self.odometry).T
            paths.append(write_trajectory_plot(os.path.join(directory, TRAJECTORY_FILE),
                                               times, x, y, yaw))
        return paths
