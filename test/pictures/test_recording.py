"""TurnRecorder fed with made-up camera images and odometry, directly and over topics."""

import math
import os
from xml.etree import ElementTree

from nav_msgs.msg import Odometry
import numpy as np
from PIL import Image as PillowImage, ImageSequence
import pytest
from rclpy.node import Node
from sensor_msgs.msg import Image
from service_tutorial.conversions import time_msg as stamp
from service_tutorial.pictures.recording import image_pixels, TurnRecorder

pytestmark = pytest.mark.ros

WIDTH, HEIGHT = 40, 30


def camera_image(seconds, encoding='rgb8', padding=0):
    """Make an image whose red level counts tenths of a second, with padded rows if asked."""
    pixels = np.zeros((HEIGHT, WIDTH, 3), dtype=np.uint8)
    pixels[..., 0] = int(round(seconds * 10)) % 256
    pixels[..., 2] = 77
    if encoding == 'bgr8':
        pixels = pixels[:, :, ::-1]
    rows = np.zeros((HEIGHT, 3 * WIDTH + padding), dtype=np.uint8)
    rows[:, :3 * WIDTH] = pixels.reshape(HEIGHT, -1)
    msg = Image(height=HEIGHT, width=WIDTH, encoding=encoding, step=3 * WIDTH + padding)
    msg.header.stamp = stamp(seconds)
    msg.data = rows.tobytes()
    return msg


def odometry(seconds, yaw):
    """Make tinybot's odometry: turning on the spot."""
    msg = Odometry()
    msg.header.stamp = stamp(seconds)
    msg.pose.pose.orientation.z = math.sin(yaw / 2)
    msg.pose.pose.orientation.w = math.cos(yaw / 2)
    return msg


@pytest.fixture
def node(rclpy_session):
    """Give a test a node for the recorder's subscriptions, not spinning."""
    recorder_node = Node('turn_recorder_test')
    yield recorder_node
    recorder_node.destroy_node()


def red_levels(recorder):
    """Return the tenths of a second each kept frame was made at."""
    return [int(frame[0, 0, 0]) for frame in recorder.frames]


def test_frames_are_kept_at_the_recording_rate(node):
    recorder = TurnRecorder(node, fps=10.0)
    for i in range(61):  # 30 frames per second for two seconds
        recorder.image_callback(camera_image(i / 30))
    assert red_levels(recorder) == list(range(0, 21))
    assert recorder.fps == 10.0


def test_a_slower_camera_gives_every_frame(node):
    recorder = TurnRecorder(node, fps=10.0)
    for i in range(11):
        recorder.image_callback(camera_image(i / 4))
    assert len(recorder.frames) == 11


def test_frames_are_thinned_when_the_cap_is_reached(node):
    recorder = TurnRecorder(node, fps=10.0, max_frames=8)
    for i in range(40):
        recorder.image_callback(camera_image(i / 10))
    levels = red_levels(recorder)
    assert len(levels) < 8 and recorder.fps < 10.0
    step = round(10 / recorder.fps)  # tenths of a second between two frames kept
    assert set(np.diff(levels)) == {step}
    assert levels[0] == 0 and levels[-1] > 39 - step, 'the whole run should stay covered'


def test_recording_goes_on_after_a_reset(node):
    recorder = TurnRecorder(node, fps=10.0)
    for seconds in (5.0, 5.1, 5.2, 0.0, 0.1):
        recorder.image_callback(camera_image(seconds))
    assert red_levels(recorder) == [50, 51, 52, 0, 1]


def test_bgr_and_padded_rows_come_out_rgb():
    pixels = image_pixels(camera_image(1.2, encoding='bgr8', padding=5))
    assert pixels.shape == (HEIGHT, WIDTH, 3)
    assert tuple(pixels[3, 4]) == (12, 0, 77)
    with pytest.raises(ValueError, match='mono8'):
        image_pixels(Image(encoding='mono8'))


def test_save_writes_the_animation_and_the_plot(node, tmp_path):
    recorder = TurnRecorder(node, fps=10.0)
    for i in range(21):
        recorder.image_callback(camera_image(i / 10))
    for i in range(101):
        recorder.odom_callback(odometry(i / 50, 0.5 * i / 50))
    paths = recorder.save(str(tmp_path / 'record'))
    assert [os.path.basename(path) for path in paths] == ['turning.gif', 'trajectory.svg']
    with open(paths[0], 'rb') as gif_file:
        assert gif_file.read(6) == b'GIF89a'
    with PillowImage.open(paths[0]) as gif:
        shown = [np.asarray(frame.convert('RGB')) for frame in ImageSequence.Iterator(gif)]
    # Every frame kept, each one the picture it was: red counts tenths of a second.
    assert [int(frame[0, 0, 0]) for frame in shown] == list(range(21))
    assert all((frame[..., 2] == 77).all() for frame in shown)
    root = ElementTree.parse(paths[1]).getroot()
    line = root.find('.//{http://www.w3.org/2000/svg}polyline[@id="heading"]')
    assert len(line.get('points').split()) == 101
    assert recorder.image_sub is None, 'save() stops the recording'


def test_nothing_recorded_saves_nothing(node, tmp_path):
    assert TurnRecorder(node).save(str(tmp_path)) == []


def test_recorder_listens_on_the_topics(ros, tmp_path):
    recorder = TurnRecorder(ros.add_node(Node('turn_recorder')), fps=5.0)
    image_pub = ros.client_node.create_publisher(Image, '/mujoco/camera/image_raw', 5)
    odom_pub = ros.client_node.create_publisher(Odometry, '/odom', 50)
    assert ros.wait_for(lambda: image_pub.get_subscription_count() > 0
                        and odom_pub.get_subscription_count() > 0, timeout=5.0)
    for i in range(10):
        image_pub.publish(camera_image(i / 10))
        odom_pub.publish(odometry(i / 10, 0.1 * i))
        ros.wait_for(lambda: len(recorder.odometry) > i, timeout=2.0)
    assert ros.wait_for(lambda: len(recorder.odometry) == 10, timeout=5.0)
    assert red_levels(recorder) == [0, 2, 4, 6, 8]
