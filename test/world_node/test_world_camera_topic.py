"""The world node's camera through real subscribers and a real save_snapshot client."""

import math
import os

import numpy as np
from PIL import Image as PillowImage
import pytest
from sensor_msgs.msg import CameraInfo, Image
from service_tutorial.conversions import seconds_of as seconds
from std_srvs.srv import Trigger

pytestmark = pytest.mark.ros

IMAGE_TOPIC = '/mujoco/camera/image_raw'
INFO_TOPIC = '/mujoco/camera/camera_info'
WIDTH, HEIGHT, FOVY = 160, 120, 60.0


def png_size(path):
    """Check a PNG's structure and CRCs with Pillow, decode it; return its (width, height)."""
    with PillowImage.open(path) as png:
        assert png.format == 'PNG'
        png.verify()  # the CRC of every chunk
    with PillowImage.open(path) as png:
        assert png.mode == 'RGB', 'an 8-bit RGB PNG is expected'
        pixels = np.asarray(png)
    assert pixels.shape == (png.height, png.width, 3) and pixels.std() > 0, 'a blank picture'
    return png.width, png.height


def test_frames_arrive_at_the_camera_rate(ros):
    world = ros.start_world(camera_enabled=True, camera_rate=5.0, camera_width=WIDTH,
                            camera_height=HEIGHT, camera_fovy=FOVY)
    images = ros.subscribe(Image, IMAGE_TOPIC)
    infos = ros.subscribe(CameraInfo, INFO_TOPIC)
    assert ros.wait_for(lambda: images, timeout=10.0), 'no camera image within 10 s'
    first, sim_start = len(images), world.node.world.time
    world.wait_sim(2.0)
    count, sim_time = len(images) - first, world.node.world.time - sim_start
    # The rate is in Hz of simulation time, whatever pace a software renderer (no GPU) lets
    # the world keep; how fast it keeps it is the benchmark's business (its camera table).
    assert count == pytest.approx(5.0 * sim_time, abs=1.5), \
        f'{count} frames in {sim_time:.2f} s of simulation time, 5 per second expected'
    # Stamps are simulation time, one period apart.
    stamps = [seconds(msg.header.stamp) for msg in images]
    assert all(abs(b - a - 0.2) < 0.003 for a, b in zip(stamps, stamps[1:])), stamps

    image = images[-1]
    assert (image.width, image.height, image.encoding, image.step) == \
        (WIDTH, HEIGHT, 'rgb8', 3 * WIDTH)
    assert image.header.frame_id == 'camera_optical_frame'
    assert len(image.data) == HEIGHT * 3 * WIDTH
    assert len(set(bytes(image.data))) > 20, 'the image is blank'

    assert ros.wait_for(lambda: infos, timeout=2.0)
    info = infos[-1]
    focal = HEIGHT / 2 / math.tan(math.radians(FOVY) / 2)
    assert (info.width, info.height) == (WIDTH, HEIGHT)
    assert list(info.k) == pytest.approx(
        [focal, 0, (WIDTH - 1) / 2, 0, focal, (HEIGHT - 1) / 2, 0, 0, 1])
    assert list(info.p) == pytest.approx(
        [focal, 0, (WIDTH - 1) / 2, 0, 0, focal, (HEIGHT - 1) / 2, 0, 0, 0, 1, 0])
    assert info.header.frame_id == image.header.frame_id


def test_disabled_camera_has_no_topic_and_renders_nothing(ros):
    world = ros.start_world(paused=True)
    images = ros.subscribe(Image, IMAGE_TOPIC)
    # The world sees the subscriber, and half a second of simulation time goes by: five frames
    # at the default rate, had the camera been enabled.
    assert ros.wait_for(lambda: world.node.count_subscribers(IMAGE_TOPIC) == 1, timeout=5.0)
    world.step(world.steps(0.5))
    assert world.node.count_publishers(IMAGE_TOPIC) == 0
    assert world.node.count_publishers(INFO_TOPIC) == 0
    assert images == []
    assert world.node.camera_stream.camera.drawing is None


def test_enabled_camera_renders_only_for_a_subscriber(ros):
    world = ros.start_world(camera_enabled=True, camera_rate=20.0, camera_width=WIDTH,
                            camera_height=HEIGHT)
    assert ros.wait_for(lambda: world.node.count_publishers(IMAGE_TOPIC) == 1, timeout=5.0)
    world.wait_sim(0.5)  # ten frames, had anyone listened
    assert world.node.camera_stream.camera.drawing is None, 'rendered with nobody listening'
    assert world.node.camera_stream.next_due == math.inf, 'stepping still stops for the camera'
    # A subscriber comes and goes: frames flow, then the camera goes quiet again.
    images = []
    subscription = ros.client_node.create_subscription(Image, IMAGE_TOPIC, images.append, 10)
    assert ros.wait_for(lambda: len(images) >= 2, timeout=10.0)
    ros.destroy(subscription)
    assert ros.wait_for(lambda: world.node.camera_stream.next_due == math.inf, timeout=5.0)


def test_save_snapshot_writes_a_png_into_the_snapshot_directory(ros, tmp_path):
    directory = tmp_path / 'snapshots'
    ros.start_world(snapshot_directory=str(directory), camera_width=WIDTH,
                    camera_height=HEIGHT)
    response = ros.call(Trigger, '/mujoco/save_snapshot', Trigger.Request())
    assert response.success, response.message
    path = response.message
    assert os.path.dirname(path) == str(directory)
    assert os.listdir(directory) == [os.path.basename(path)]
    assert png_size(path) == (WIDTH, HEIGHT)
    assert os.listdir(tmp_path) == ['snapshots'], 'nothing is written anywhere else'


def test_save_snapshot_reports_a_directory_it_cannot_write(ros, tmp_path):
    blocker = tmp_path / 'a_file'
    blocker.write_text('not a directory')
    ros.start_world(snapshot_directory=str(blocker / 'snapshots'), camera_width=WIDTH,
                    camera_height=HEIGHT)
    response = ros.call(Trigger, '/mujoco/save_snapshot', Trigger.Request())
    assert not response.success
    assert 'could not save a snapshot' in response.message
