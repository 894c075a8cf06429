"""
The lesson's own tinybot (xacro, Gazebo blocks of ROS 1) publishes its sensors as in Gazebo.

It comes from the lesson's files beside the repository (../shared/lesson/robots), expanded by
the xacro package once gcamp_gazebo is an ament package in a temporary prefix, and is spawned
through /mujoco/spawn_urdf_model with robot_namespace tb2, as the Gazebo lesson spawns it, into
a paused world the test steps.
"""

import math
import os
import shutil

import numpy as np
import pytest
from rclpy.node import Node
from repository import LESSON_ROBOTS
from sensor_msgs.msg import CameraInfo, Image, Imu, LaserScan
from service_tutorial.conversions import make_pose, seconds_of as seconds
from srv_interfaces.srv import SpawnModel

GCAMP_GAZEBO = os.path.join(LESSON_ROBOTS, 'gcamp_gazebo')
# Wall time the first 800x800 camera frame may take, drawn on a busy machine, in s.
FRAME_TIMEOUT = 60.0

pytest_plugins = ['service_tutorial.testing.fixtures']
pytestmark = [
    pytest.mark.ros,
    pytest.mark.skipif(not os.path.isdir(GCAMP_GAZEBO),
                       reason=f'the lesson robots are not beside the repository: no '
                       f'{GCAMP_GAZEBO}'),
]


@pytest.fixture
def lesson_tinybot(tmp_path, monkeypatch):
    """Return the lesson's tinybot as URDF, gcamp_gazebo installed in a temporary prefix."""
    import xacro
    prefix = tmp_path / 'prefix'
    markers = prefix / 'share' / 'ament_index' / 'resource_index' / 'packages'
    markers.mkdir(parents=True)
    (markers / 'gcamp_gazebo').touch()
    shutil.copytree(GCAMP_GAZEBO, prefix / 'share' / 'gcamp_gazebo')
    monkeypatch.setenv('AMENT_PREFIX_PATH',
                       os.pathsep.join([str(prefix), os.environ.get('AMENT_PREFIX_PATH', '')]))
    source = prefix / 'share' / 'gcamp_gazebo' / 'urdf' / 'tinybot_diff.xacro'
    return xacro.process_file(str(source), mappings={}).toxml()


def test_the_lesson_tinybot_publishes_scan_camera_and_imu(mujoco_sim, lesson_tinybot):
    world = mujoco_sim
    listener = world.add_node(Node('sensor_listener', context=world.context))
    # The lesson's world holds its tinybot alone, in the yard: the project's makes way.
    world.delete_entity('tinybot')
    # The footprint is at the wheel axle.
    spawned = world.call(SpawnModel, '/mujoco/spawn_urdf_model', SpawnModel.Request(
        model_name='tinybot', model_xml=lesson_tinybot, robot_namespace='tb2',
        initial_pose=make_pose(0.0, 0.0, 0.1)))
    assert spawned.success, spawned.status_message
    # /scan is absolute; imu/data and the camera's are relative, so under tb2 (as in Gazebo).
    node = world.world_node
    assert world.wait_for(lambda: all(model.topics_made for model in list(node.models.values())))
    published = {publisher.topic_name
                 for publisher in list(node.publishers) + node.sensor_node.publishers}
    assert {'/scan', '/tb2/imu/data', '/tb2/camera/rgb/image_raw',
            '/tb2/camera/rgb/camera_info'} <= published
    received = {}
    for msg_type, topic in ((LaserScan, '/scan'), (Imu, '/tb2/imu/data'),
                            (Image, '/tb2/camera/rgb/image_raw'),
                            (CameraInfo, '/tb2/camera/rgb/camera_info')):
        received[topic] = []
        listener.create_subscription(msg_type, topic, received[topic].append, 10)
    world.step(round(1.0 / world.timestep))  # tinybot settles on its wheels
    imus = received['/tb2/imu/data']
    # A long request of steps holds each stream to its rate in wall time too: a few more steps
    # at a time until the IMU speaks of the settled robot.
    for _ in range(100):
        if imus and seconds(imus[-1].header.stamp) >= 1.0:
            break
        world.step(10)
    assert imus and seconds(imus[-1].header.stamp) >= 1.0, 'no IMU message once settled'
    # The camera draws in the background: its frame comes once drawn, a tick of the world later.
    assert world.wait_for(lambda: all(received.values()), timeout=FRAME_TIMEOUT), \
        {topic: len(messages) for topic, messages in received.items()}

    scan = received['/scan'][0]
    ranges = np.array(scan.ranges)
    assert len(ranges) == 720 and scan.header.frame_id == 'hokuyo'
    assert scan.angle_increment == pytest.approx(math.pi / 719, abs=1e-6)
    assert (scan.range_min, scan.range_max) == pytest.approx((0.1, 30.0))
    # Straight ahead, the yard's east wall: 5 m from the robot, less the hokuyo's 0.15 m.
    assert ranges[360] == pytest.approx(4.85, abs=0.05)
    print(f'/scan at t={seconds(scan.header.stamp):.3f} s: {len(ranges)} ranges, '
          f'frame {scan.header.frame_id}, ranges[0] {ranges[0]:.3f} m (right), '
          f'ranges[360] {ranges[360]:.3f} m (ahead), ranges[719] {ranges[719]:.3f} m (left)')

    imu = imus[-1]  # tinybot settled on its wheels
    acceleration = imu.linear_acceleration
    assert acceleration.z == pytest.approx(9.81, abs=0.05)
    print(f'/tb2/imu/data at t={seconds(imu.header.stamp):.3f} s: frame '
          f'{imu.header.frame_id}, orientation (x, y, z, w) ({imu.orientation.x:.4f}, '
          f'{imu.orientation.y:.4f}, {imu.orientation.z:.4f}, {imu.orientation.w:.4f}), '
          f'linear_acceleration ({acceleration.x:.3f}, {acceleration.y:.3f}, '
          f'{acceleration.z:.3f}) m/s^2')

    image = received['/tb2/camera/rgb/image_raw'][0]
    info = received['/tb2/camera/rgb/camera_info']
    assert (image.width, image.height, image.encoding) == (800, 800, 'rgb8')
    assert image.header.frame_id == 'camera'
    pixels = np.frombuffer(bytes(image.data), dtype=np.uint8).reshape(800, 800, 3)
    assert pixels.std() > 10, 'a blank image'
    focal = 400 / math.tan(1.3962634 / 2)
    assert info[-1].k[0] == pytest.approx(focal) and info[-1].p[3] == pytest.approx(
        -focal * 0.07)
    print(f'/tb2/camera/rgb/image_raw at t={seconds(image.header.stamp):.3f} s: '
          f'{image.width}x{image.height} {image.encoding}, frame {image.header.frame_id}, '
          f'centre pixel {pixels[400, 400].tolist()}, fx {info[-1].k[0]:.1f}')
