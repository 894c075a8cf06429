"""
The lesson's own tinybot (xacro, Gazebo blocks of ROS 1) publishes its sensors as in Gazebo.

It comes from the lesson's files beside the repository (../shared/lesson/robots), expanded by
the xacro package once gcamp_gazebo is an ament package in a temporary prefix, and is spawned
through /mujoco/spawn_urdf_model with robot_namespace tb2, as the Gazebo lesson spawns it.
"""

import math
import os
import shutil

import numpy as np
import pytest
from repository import LESSON_ROBOTS
from sensor_msgs.msg import CameraInfo, Image, Imu, LaserScan
from service_tutorial.conversions import make_pose, seconds_of as seconds

GCAMP_GAZEBO = os.path.join(LESSON_ROBOTS, 'gcamp_gazebo')

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


def test_the_lesson_tinybot_publishes_scan_camera_and_imu(ros, lesson_tinybot):
    world = ros.start_world(real_time_factor=0.0)
    # The lesson's world holds its tinybot alone, in the yard: the project's makes way.
    deleted = world.delete('tinybot')
    assert deleted.success, deleted.status_message
    # The footprint is at the wheel axle.
    world.spawn_or_fail('tinybot', lesson_tinybot, make_pose(0.0, 0.0, 0.1), namespace='tb2')
    # /scan is absolute; imu/data and the camera's are relative, so under tb2 (as in Gazebo).
    assert {'/scan', '/tb2/imu/data', '/tb2/camera/rgb/image_raw',
            '/tb2/camera/rgb/camera_info'} <= world.published_topics()

    scan = ros.receive(LaserScan, '/scan', timeout=60.0)[0]
    ranges = np.array(scan.ranges)
    assert len(ranges) == 720 and scan.header.frame_id == 'hokuyo'
    assert scan.angle_increment == pytest.approx(math.pi / 719, abs=1e-6)
    assert (scan.range_min, scan.range_max) == pytest.approx((0.1, 30.0))
    # Straight ahead, the yard's east wall: 5 m from the robot, less the hokuyo's 0.15 m.
    assert ranges[360] == pytest.approx(4.85, abs=0.05)
    print(f'/scan at t={seconds(scan.header.stamp):.3f} s: {len(ranges)} ranges, '
          f'frame {scan.header.frame_id}, ranges[0] {ranges[0]:.3f} m (right), '
          f'ranges[360] {ranges[360]:.3f} m (ahead), ranges[719] {ranges[719]:.3f} m (left)')

    imu = ros.receive(Imu, '/tb2/imu/data', timeout=60.0)[0]
    acceleration = imu.linear_acceleration
    assert acceleration.z == pytest.approx(9.81, abs=0.05)
    print(f'/tb2/imu/data at t={seconds(imu.header.stamp):.3f} s: frame '
          f'{imu.header.frame_id}, orientation (x, y, z, w) ({imu.orientation.x:.4f}, '
          f'{imu.orientation.y:.4f}, {imu.orientation.z:.4f}, {imu.orientation.w:.4f}), '
          f'linear_acceleration ({acceleration.x:.3f}, {acceleration.y:.3f}, '
          f'{acceleration.z:.3f}) m/s^2')

    info = ros.subscribe(CameraInfo, '/tb2/camera/rgb/camera_info')
    image = ros.receive(Image, '/tb2/camera/rgb/image_raw', timeout=120.0)[0]
    assert (image.width, image.height, image.encoding) == (800, 800, 'rgb8')
    assert image.header.frame_id == 'camera'
    pixels = np.frombuffer(bytes(image.data), dtype=np.uint8).reshape(800, 800, 3)
    assert pixels.std() > 10, 'a blank image'
    assert ros.wait_for(lambda: info, timeout=60.0)
    focal = 400 / math.tan(1.3962634 / 2)
    assert info[-1].k[0] == pytest.approx(focal) and info[-1].p[3] == pytest.approx(
        -focal * 0.07)
    print(f'/tb2/camera/rgb/image_raw at t={seconds(image.header.stamp):.3f} s: '
          f'{image.width}x{image.height} {image.encoding}, frame {image.header.frame_id}, '
          f'centre pixel {pixels[400, 400].tolist()}, fx {info[-1].k[0]:.1f}')
