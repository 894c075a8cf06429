"""Sensors through their ROS topics on a real world node: LaserScan, Image, CameraInfo, Imu."""

import math
import time

import numpy as np
import pytest
from repository import read_model, TEST_MODELS
from sensor_msgs.msg import CameraInfo, Image, Imu, LaserScan
from service_tutorial.conversions import make_pose, seconds_of as seconds
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.plugins.ray_sensor import RaySensor

pytestmark = pytest.mark.ros


def assert_stops(world, sensor):
    """Wait until the world sees nobody listens to a sensor; then it measures no more."""
    assert world.ros.wait_for(lambda: not sensor.active, timeout=10.0)
    last = sensor.reading_time
    world.wait_sim(0.5)
    assert sensor.reading_time == last


def test_laser_scan_on_its_topic_only_while_someone_listens(ros):
    world = ros.start_world(scenery='', real_time_factor=2.0)
    world.spawn_or_fail('post', read_model('sensor_laser', TEST_MODELS), namespace='post')
    world.spawn_or_fail('wall', read_model('props/wall', TEST_MODELS), make_pose(1.05))
    assert '/post/scan' in world.published_topics()
    laser = world.node.world.models['post'].plugin(RaySensor)
    world.wait_sim(0.5)
    assert laser.reading_time is None, 'the laser scanned with nobody listening'

    scans = ros.receive(LaserScan, '/post/scan', count=5)
    scan = scans[-1]
    assert scan.header.frame_id == 'laser_frame'
    assert len(scan.ranges) == 181
    assert scan.angle_min == pytest.approx(-math.pi / 2, abs=1e-6)
    assert scan.angle_max == pytest.approx(math.pi / 2, abs=1e-6)
    assert scan.angle_increment == pytest.approx(math.pi / 180, abs=1e-6)
    assert (scan.range_min, scan.range_max) == pytest.approx((0.05, 5.0))
    assert scan.scan_time == pytest.approx(0.1)
    assert scan.ranges[90] == pytest.approx(1.0, abs=0.005)
    assert math.isinf(scan.ranges[0]) and scan.ranges[0] > 0
    # 10 Hz in simulation time, stamped with it.
    stamps = [seconds(msg.header.stamp) for msg in scans]
    assert np.diff(stamps[1:]) == pytest.approx([0.1] * (len(stamps) - 2), abs=1e-6)
    # The subscriber left: the laser stops (the world hears of it, then scans no more).
    assert_stops(world, laser)


def test_free_running_a_sensor_is_held_to_its_rate_in_wall_time_too(ros):
    world = ros.start_world(scenery='', real_time_factor=0.0)
    world.spawn_or_fail('post', read_model('sensor_laser', TEST_MODELS), namespace='post')
    world.spawn_or_fail('wall', read_model('props/wall', TEST_MODELS), make_pose(1.05))
    scans = []
    subscription = ros.client_node.create_subscription(LaserScan, '/post/scan', scans.append, 10)
    try:
        assert ros.wait_for(lambda: scans, timeout=10.0)
        start, first = time.monotonic(), len(scans)
        sim_start = world.node.world.time
        assert ros.wait_for(lambda: world.node.world.time > sim_start + 20.0 and
                            len(scans) >= first + 3, timeout=60.0)
        wall = time.monotonic() - start
        count = len(scans) - first
    finally:
        ros.destroy(subscription)
    # 10 Hz of simulation time would be 200 scans; held to 10 per wall second, far fewer.
    assert count <= 10.0 * wall + 2, f'{count} scans in {wall:.2f} s of wall time'
    stamps = [seconds(msg.header.stamp) for msg in scans]
    assert all(np.diff(stamps) >= 0.1 - 1e-6), stamps
    assert all(msg.ranges[90] == pytest.approx(1.0, abs=0.005) for msg in scans)


def test_camera_image_and_camera_info_of_a_ros1_camera(ros):
    world = ros.start_world(scenery='', real_time_factor=0.0)
    world.spawn_or_fail('eye', read_model('sensor_camera', TEST_MODELS), namespace='eye')
    world.spawn_or_fail('box', read_model('props/red_box', TEST_MODELS), make_pose(1.5))
    # ROS 1: robotNamespace/cameraName/imageTopicName.
    assert {'/eye/front/rgb/image_raw', '/eye/front/rgb/camera_info'} <= world.published_topics()
    infos = ros.subscribe(CameraInfo, '/eye/front/rgb/camera_info')
    image = ros.receive(Image, '/eye/front/rgb/image_raw')[0]
    assert (image.width, image.height, image.encoding, image.step) == (160, 120, 'rgb8', 480)
    assert image.header.frame_id == 'camera_link'
    pixels = np.frombuffer(bytes(image.data), dtype=np.uint8).reshape(120, 160, 3).astype(int)
    r, g, b = pixels[60, 80]
    assert r > 2 * g and r > 2 * b, f'the centre is {pixels[60, 80]}, not red'
    for row, column in ((60, 0), (60, 159), (0, 80)):
        r, g, b = pixels[row, column]
        assert not (r > 2 * g and r > 2 * b), f'({row}, {column}) is red'
    assert ros.wait_for(lambda: infos, timeout=10.0)
    info = infos[-1]
    focal = 160 / 2 / math.tan(1.0 / 2)
    assert list(info.k) == pytest.approx([focal, 0, 79.5, 0, focal, 59.5, 0, 0, 1])
    assert (info.width, info.height, info.distortion_model) == (160, 120, 'plumb_bob')


def test_the_default_tinybots_ros2_camera_renders_at_its_rate_only_while_watched(ros):
    world = ros.start_world(real_time_factor=2.0)
    # ROS 2: <camera_name>camera</camera_name> and no namespace.
    assert {'/camera/image_raw', '/camera/camera_info'} <= world.published_topics()
    camera = world.node.world.models['tinybot'].plugin(CameraSensor)
    infos = []
    info_subscription = ros.client_node.create_subscription(
        CameraInfo, '/camera/camera_info', infos.append, 10)
    images = ros.receive(Image, '/camera/image_raw', count=4)
    image = images[-1]
    assert (image.width, image.height, image.encoding, image.step) == (320, 240, 'rgb8', 960)
    assert image.header.frame_id == 'camera_link'
    pixels = np.frombuffer(bytes(image.data), dtype=np.uint8).reshape(240, 320, 3)
    assert pixels.std() > 10.0, 'the yard should not look like one flat colour'
    # 10 Hz in simulation time, stamped with it; a frame that would fall due while the one
    # before is still being drawn is skipped (software rendering can be slower than 10 Hz),
    # and the next comes a whole number of periods later, give or take a physics step.
    stamps = [seconds(msg.header.stamp) for msg in images]
    gaps = np.diff(stamps)
    assert np.all(gaps >= 0.1 - 1e-6), stamps
    assert gaps / 0.1 == pytest.approx(np.round(gaps / 0.1), abs=0.002 / 0.1 + 1e-6), stamps
    assert ros.wait_for(lambda: infos, timeout=10.0)
    focal = 320 / 2 / math.tan(1.3962634 / 2)
    assert list(infos[-1].k) == pytest.approx([focal, 0, 159.5, 0, focal, 119.5, 0, 0, 1])
    assert infos[-1].header.frame_id == 'camera_link'
    # Nobody watches any more: the camera stops rendering.
    ros.destroy(info_subscription)
    assert_stops(world, camera)


def test_imus_of_both_generations_read_gravity_up(ros):
    world = ros.start_world()
    world.spawn_or_fail('imu_bot', read_model('sensor_imu', TEST_MODELS), make_pose(0.0, -2.0),
                        namespace='bot')
    # The default tinybot's IMU (ROS 2, ~/out:=imu) and the spawned robot's two.
    topics = {'/imu': 'base_link', '/bot/imu/data': 'base_footprint', '/bot/imu': 'imu_link'}
    assert set(topics) <= world.published_topics()
    for topic, frame in topics.items():
        msg = ros.receive(Imu, topic, count=3)[-1]
        assert msg.header.frame_id == frame
        assert msg.linear_acceleration.z == pytest.approx(9.81, abs=0.05), topic
        assert msg.angular_velocity.z == pytest.approx(0.0, abs=0.01), topic
        assert abs(msg.orientation.w) == pytest.approx(
            1.0 if topic != '/bot/imu' else math.sqrt(0.5), abs=0.01)


def test_the_default_world_has_the_yard_as_scenery_not_as_a_model(ros):
    world = ros.start_world(real_time_factor=0.0)
    assert world.models() == ['tinybot']
    scan = ros.receive(LaserScan, '/scan')[0]
    ranges = np.array(scan.ranges)
    assert len(ranges) == 360 and scan.header.frame_id == 'base_scan'
    # Straight ahead, the yard's east wall 5 m away; every beam meets a wall or a crate.
    assert ranges[180] == pytest.approx(4.98, abs=0.05)
    assert np.isfinite(ranges).all()


def test_sensor_topics_come_from_the_world_sensor_node_and_go_with_their_model(ros):
    world = ros.start_world(scenery='')
    world.spawn_or_fail('post', read_model('sensor_laser', TEST_MODELS), namespace='post')
    assert '/post/scan' in world.published_topics()

    def scan_publishers():
        return [(info.node_namespace, info.node_name)
                for info in ros.client_node.get_publishers_info_by_topic('/post/scan')]
    # A node of its own, in a participant of its own, beside the world node 'mujoco'.
    assert ros.wait_for(lambda: scan_publishers() == [('/', 'mujoco_sensors')])
    assert ros.receive(LaserScan, '/post/scan', count=1)[0].header.frame_id == 'laser_frame'
    assert world.delete('post').success
    assert ros.wait_for(lambda: scan_publishers() == [])
