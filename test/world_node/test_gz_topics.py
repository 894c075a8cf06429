"""
gz-sim's systems and sensors on their ROS topics, as ros_gz_bridge serves them, in sim time.

The world is the suite's SDF world test/models/sdf/worlds/proving_ground.sdf (its origin on
the Earth, a wall at x = 2 m); the suite's own robots with gz-sim blocks (surveyor, an SDF
model; gzbot, a URDF; burger, a TurtleBot3 Burger-like SDF) are spawned into it, paused, and
stepped through the deterministic fixture (service_tutorial.testing): every topic is the gz
topic of the same name with the bridge's default ROS type, or what a GzBridge mapping says.
"""

import math
import os

from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
import numpy as np
import pytest
from rclpy.node import Node
from repository import read_file, TEST_MODELS
from sensor_msgs.msg import CameraInfo, PointField
from sensor_msgs.msg import Image, Imu, JointState, LaserScan, NavSatFix, PointCloud2
from service_tutorial.conversions import seconds_of
from service_tutorial.world_node.gz_bridge import BridgedTopic, GZ_TO_ROS, GzBridge, ROS_TO_GZ
from std_msgs.msg import Float64
from tf2_msgs.msg import TFMessage

pytestmark = pytest.mark.ros
pytest_plugins = ['service_tutorial.testing.fixtures']

SDF = os.path.join(TEST_MODELS, 'sdf')
PROVING_GROUND = os.path.join(SDF, 'worlds', 'proving_ground.sdf')
SURVEYOR = os.path.join(SDF, 'models', 'surveyor', 'model.sdf')
BURGER = os.path.join(SDF, 'models', 'burger', 'model.sdf')
GZBOT = os.path.join(TEST_MODELS, 'gzbot.urdf')
TIMESTEP = 0.001  # the world's max_step_size
WALL = 2.0  # m, x of the wall's face
ORIGIN = (48.8584, 2.2945, 35.0)  # the world's <spherical_coordinates>
SURVEYOR_SENSORS = '/world/proving_ground/model/surveyor/link/chassis/sensor/'


def steps(seconds):
    return round(seconds / TIMESTEP)


class Listener(Node):
    """A user's node: keeps what comes on topics, and publishes commands."""

    def __init__(self, **kwargs):
        super().__init__('gz_listener', **kwargs)
        self.received = {}

    def listen(self, msg_type, topic):
        """Keep every message of a topic from now on; return their list."""
        received = self.received.setdefault(topic, [])
        # Deep enough for every message of a second's steps, taken faster than they come.
        self.create_subscription(msg_type, topic, received.append, 1000)
        return received


@pytest.fixture
def world(mujoco_sim_factory):
    """Start the proving ground, paused, with a listener node."""
    sim = mujoco_sim_factory(world=PROVING_GROUND)
    sim.listener = sim.add_node(Listener(context=sim.context))
    return sim


def spawn(world, name, path, pose=(0.0, 0.0, 0.0)):
    world.spawn_entity(name, read_file(path), pose)
    world.step(steps(0.3))  # the robot settles on its wheels


def command(world, topic, msg_type, linear_x):
    publisher = world.listener.create_publisher(msg_type, topic, 10)
    assert world.wait_for(lambda: publisher.get_subscription_count() > 0)
    msg = msg_type()
    (msg.twist if msg_type is TwistStamped else msg).linear.x = linear_x
    publisher.publish(msg)


def drive_for_a_second(world, name, topic, msg_type):
    """Command 0.2 m/s on a topic for 1 s of simulation time; return the distance travelled."""
    start = world.entity_state(name).pose.position
    command(world, topic, msg_type, 0.2)
    world.step(steps(1.0))
    end = world.entity_state(name).pose.position
    return math.hypot(end.x - start.x, end.y - start.y)


@pytest.mark.parametrize('name, path, cmd_vel', [
    ('surveyor', SURVEYOR, '/model/surveyor/cmd_vel'), ('gzbot', GZBOT, '/cmd_vel')])
def test_robots_drive_on_their_gz_cmd_vel_as_twist(world, name, path, cmd_vel):
    spawn(world, name, path)
    travelled = drive_for_a_second(world, name, cmd_vel, Twist)
    print(f'\n{name}: 0.2 m/s on {cmd_vel} (Twist) for 1 s travelled {travelled:.4f} m')
    assert 0.19 <= travelled <= 0.21


@pytest.mark.parametrize('name, path, cmd_vel', [
    ('surveyor', SURVEYOR, '/model/surveyor/cmd_vel'), ('gzbot', GZBOT, '/cmd_vel')])
def test_a_bridge_mapping_makes_cmd_vel_twist_stamped(world, name, path, cmd_vel):
    world.world_node.gz_bridge = GzBridge([BridgedTopic(
        cmd_vel, 'gz.msgs.Twist', 'cmd_vel_stamped', TwistStamped, ROS_TO_GZ)])
    spawn(world, name, path)
    assert world.listener.count_subscribers(cmd_vel) == 0
    travelled = drive_for_a_second(world, name, '/cmd_vel_stamped', TwistStamped)
    print(f'\n{name}: 0.2 m/s on /cmd_vel_stamped (TwistStamped) for 1 s travelled '
          f'{travelled:.4f} m')
    assert 0.19 <= travelled <= 0.21


@pytest.mark.parametrize('name, path, topics, frames', [
    ('surveyor', SURVEYOR,
     ('/world/proving_ground/model/surveyor/joint_state', '/model/surveyor/odometry', '/tf'),
     ('odom', 'chassis')),
    ('gzbot', GZBOT, ('/joint_states', '/odom', '/tf'), ('odom', 'base_footprint'))])
def test_joint_states_odometry_and_tf_in_the_declared_frames(world, name, path, topics,
                                                             frames):
    spawn(world, name, path)
    joint_topic, odom_topic, tf_topic = topics
    joints = world.listener.listen(JointState, joint_topic)
    odometry = world.listener.listen(Odometry, odom_topic)
    transforms = world.listener.listen(TFMessage, tf_topic)
    command(world, '/model/surveyor/cmd_vel' if name == 'surveyor' else '/cmd_vel', Twist, 0.2)
    world.step(steps(1.0))
    assert joints and odometry and transforms
    state = joints[-1]
    assert list(state.name) == ['left_wheel_joint', 'right_wheel_joint']
    radius = 0.05 if name == 'surveyor' else 0.04
    assert state.velocity == pytest.approx([0.2 / radius] * 2, rel=0.05)
    assert len(state.effort) == 2
    odom = odometry[-1]
    assert (odom.header.frame_id, odom.child_frame_id) == frames
    assert seconds_of(odom.header.stamp) == pytest.approx(world.time, abs=0.04)
    assert odom.pose.pose.position.x == pytest.approx(0.195, abs=0.01)
    assert odom.twist.twist.linear.x == pytest.approx(0.2, abs=0.01)
    transform = transforms[-1].transforms[0]
    assert (transform.header.frame_id, transform.child_frame_id) == frames
    assert transform.transform.translation.x == pytest.approx(0.195, abs=0.01)
    # Odometry at its frequency: surveyor's default 50 Hz, gzbot's 30 Hz.
    period = 0.02 if name == 'surveyor' else 1.0 / 30.0
    stamps = [seconds_of(msg.header.stamp) for msg in odometry]
    assert np.diff(stamps) == pytest.approx([period] * (len(stamps) - 1), abs=TIMESTEP * 1.01)


def cloud_points(cloud):
    """Return a PointCloud2's points as a numpy structured array (float32 and uint16 fields)."""
    kinds = {PointField.FLOAT32: '<f4', PointField.UINT16: '<u2'}
    dtype = np.dtype({'names': [field.name for field in cloud.fields],
                      'formats': [kinds[field.datatype] for field in cloud.fields],
                      'offsets': [field.offset for field in cloud.fields],
                      'itemsize': cloud.point_step})
    return np.frombuffer(bytes(cloud.data), dtype=dtype)


def reading_after(world, received, stamp):
    """
    Step until a reading stamped at stamp or later comes; return it.

    Stepped on request, the world holds each sensor to its rate in wall time too
    (faces/sensor.py): a 5 Hz lidar scans once per 0.2 s of wall time, however fast the steps.
    """
    def came():
        if not (received and seconds_of(received[-1].header.stamp) >= stamp - 1e-9):
            world.step(steps(0.1))
            return False
        return True
    assert world.wait_for(came, timeout=30.0), f'no reading after {stamp} s'
    return received[-1]


def latest(world, msg_type, topic, seconds=0.5):
    """Listen to a topic for some seconds of simulation time; return the last message."""
    received = world.listener.listen(msg_type, topic)
    world.step(steps(seconds))
    # A camera draws in the background: its frame comes once drawn, a tick of the world later.
    assert world.wait_for(lambda: received), f'nothing on {topic}'
    return received[-1]


def test_a_gz_lidar_reads_the_wall_on_its_default_topic(world):
    spawn(world, 'surveyor', SURVEYOR)
    scan = latest(world, LaserScan, SURVEYOR_SENSORS + 'front_lidar/scan')
    assert scan.header.frame_id == 'surveyor/chassis/front_lidar'
    assert len(scan.ranges) == 181 and scan.angle_increment == pytest.approx(math.pi / 180)
    assert (scan.range_min, scan.range_max) == pytest.approx((0.1, 8.0))
    expected = WALL - (world.entity_state('surveyor').pose.position.x + 0.1)
    print(f'\nsurveyor gpu_lidar: the wall {expected:.4f} m ahead reads {scan.ranges[90]:.4f} m')
    assert scan.ranges[90] == pytest.approx(expected, abs=0.02)
    assert scan.ranges[90] != pytest.approx(expected, abs=1e-4)  # its declared noise


def test_a_depth_cameras_centre_pixel_reads_the_wall(world):
    spawn(world, 'surveyor', SURVEYOR)
    topic = SURVEYOR_SENSORS + 'depth/depth_image'
    points = world.listener.listen(PointCloud2, topic + '/points')
    image = latest(world, Image, topic, seconds=0.5)
    assert (image.width, image.height, image.encoding) == (64, 48, '32FC1')
    depth = np.frombuffer(bytes(image.data), dtype=np.float32).reshape(48, 64)
    expected = WALL - (world.entity_state('surveyor').pose.position.x + 0.15)
    centre = float(depth[23:25, 31:33].mean())
    print(f'\nsurveyor depth camera: the wall {expected:.4f} m ahead reads {centre:.4f} m at '
          'its centre')
    assert centre == pytest.approx(expected, abs=0.02)
    assert world.wait_for(lambda: points), 'no points'
    cloud = points[-1]
    assert (cloud.height, cloud.width) == (48, 64)
    points = cloud_points(cloud).reshape(48, 64)
    # The middle row meets the wall across the image; the bottom rows the floor, nearer.
    assert points['x'][24] == pytest.approx([expected] * 64, abs=0.02)
    assert points['y'][24, 0] > 0.9 and points['y'][24, 63] < -0.9  # left is +y
    assert (points['x'][47] < 0.5).all() and (points['z'][47] < 0.0).all()


def test_an_imu_reads_gravity_and_a_navsat_the_worlds_origin(world):
    spawn(world, 'surveyor', SURVEYOR)
    imu_topic, navsat_topic = (SURVEYOR_SENSORS + 'imu/imu', SURVEYOR_SENSORS + 'gps/navsat')
    fixes = world.listener.listen(NavSatFix, navsat_topic)
    imu = latest(world, Imu, imu_topic)
    print(f'\nsurveyor IMU at rest: linear acceleration z {imu.linear_acceleration.z:.4f} '
          'm/s^2')
    assert imu.linear_acceleration.z == pytest.approx(9.8, abs=0.05)
    assert imu.angular_velocity.z == pytest.approx(0.0, abs=0.01)
    assert abs(imu.orientation.w) == pytest.approx(1.0, abs=1e-3)
    assert imu.header.frame_id == 'surveyor/chassis/imu'
    fix = fixes[-1]
    height = world.entity_state('surveyor').pose.position.z + 0.05
    print(f'surveyor NavSat at the origin: {fix.latitude:.7f} {fix.longitude:.7f} '
          f'{fix.altitude:.4f} m')
    assert fix.header.frame_id == 'gps_link'
    assert (fix.latitude, fix.longitude) == pytest.approx(ORIGIN[:2], abs=1e-7)
    assert fix.altitude == pytest.approx(ORIGIN[2] + height, abs=0.01)


def test_a_lidar_of_three_rows_gives_its_middle_row_and_its_points(world):
    spawn(world, 'gzbot', GZBOT)
    points = world.listener.listen(PointCloud2, '/scan/points')
    scan = latest(world, LaserScan, '/scan')
    assert scan.header.frame_id == 'base_link' and len(scan.ranges) == 90
    expected = WALL - (world.entity_state('gzbot').pose.position.x + 0.05)
    middle = scan.ranges[44:46]
    print(f'\ngzbot lidar: the wall {expected:.4f} m ahead reads {list(middle)}')
    assert middle == pytest.approx([expected / math.cos(math.pi / 4 / 89)] * 2, abs=0.02)
    cloud = points[-1]
    assert (cloud.height, cloud.width) == (3, 90)
    assert [field.name for field in cloud.fields] == ['x', 'y', 'z', 'intensity', 'ring']
    rows = cloud_points(cloud).reshape(3, 90)
    assert (rows['ring'] == np.array([[0], [1], [2]])).all()
    # The rows look 0.1 rad down (to the floor, 0.13 m below), level and 0.1 rad up (the wall).
    height = world.entity_state('gzbot').pose.position.z + 0.07 + 0.06
    floor = height / math.tan(0.1)
    assert rows['x'][:, 44] == pytest.approx([floor, expected, expected], abs=0.02)
    assert rows['z'][:, 44] == pytest.approx([-height, 0.0, expected * math.tan(0.1)],
                                             abs=0.02)


def test_a_turtlebot3_burger_like_robot_spawns_drives_and_scans(world):
    spawn(world, 'burger', BURGER)
    scans = world.listener.listen(LaserScan, '/scan')
    imu = world.listener.listen(Imu, '/imu')
    odometry = world.listener.listen(Odometry, '/odom')
    travelled = drive_for_a_second(world, 'burger', '/cmd_vel', Twist)
    print(f'\nburger: 0.2 m/s on /cmd_vel for 1 s (1 m/s^2 up) travelled {travelled:.4f} m')
    assert travelled == pytest.approx(0.2 - 0.2 * 0.2 / 2.0, abs=0.01)
    command(world, '/cmd_vel', Twist, 0.0)
    world.step(steps(0.5))  # it stops, 0.2 s later
    scan = reading_after(world, scans, world.time)
    assert scan.header.frame_id == 'base_scan' and len(scan.ranges) == 360
    ahead = WALL - (world.entity_state('burger').pose.position.x - 0.032)
    print(f'burger: the wall {ahead:.4f} m ahead reads {scan.ranges[0]:.4f} m')
    assert scan.ranges[0] == pytest.approx(ahead, abs=0.04)  # 1 cm noise
    assert imu[-1].header.frame_id == 'burger/imu_link/tb3_imu'
    assert imu[-1].linear_acceleration.z == pytest.approx(9.8, abs=0.1)
    assert (odometry[-1].header.frame_id, odometry[-1].child_frame_id) == \
        ('odom', 'base_footprint')


def test_a_new_bridge_remakes_the_topics_and_the_robot_runs_on(world):
    spawn(world, 'surveyor', SURVEYOR)
    scan_topic = SURVEYOR_SENSORS + 'front_lidar/scan'
    scans = world.listener.listen(LaserScan, '/front_scan')
    drive_for_a_second(world, 'surveyor', '/model/surveyor/cmd_vel', Twist)
    world.world_node.set_gz_bridge(GzBridge([
        BridgedTopic('/model/surveyor/cmd_vel', 'gz.msgs.Twist', '/cmd_vel', TwistStamped,
                     ROS_TO_GZ),
        BridgedTopic(scan_topic, 'gz.msgs.LaserScan', '/front_scan', LaserScan, GZ_TO_ROS)]))
    node = world.listener
    assert world.wait_for(lambda: (
        node.count_subscribers('/model/surveyor/cmd_vel'), node.count_subscribers('/cmd_vel'),
        node.count_publishers(scan_topic), node.count_publishers('/front_scan')) ==
        (0, 1, 0, 1))
    # The robot kept its command and its state: it drives on from where it was.
    start = world.entity_state('surveyor').pose.position.x
    world.step(steps(0.5))
    assert world.entity_state('surveyor').pose.position.x == pytest.approx(start + 0.1,
                                                                           abs=0.005)
    # Commanded on the new topic, as TwistStamped: it stops; its lidar scans on /front_scan.
    command(world, '/cmd_vel', TwistStamped, 0.0)
    world.step(steps(0.2))
    assert world.entity_state('surveyor').twist.linear.x == pytest.approx(0.0, abs=0.005)
    scan = reading_after(world, scans, world.time)
    expected = WALL - (world.entity_state('surveyor').pose.position.x + 0.1)
    assert scan.ranges[90] == pytest.approx(expected, abs=0.02)
    assert scan.header.frame_id == 'surveyor/chassis/front_lidar'


ARM = """<sdf version="1.9"><model name="arm">
  <link name="base"><collision name="c"><geometry><box><size>0.2 0.2 0.1</size></box>
    </geometry></collision></link>
  <joint name="anchor" type="fixed"><parent>world</parent><child>base</child></joint>
  <link name="arm"><pose>0 0 0.3 0 0 0</pose>
    <inertial><pose>0 0 0.1 0 0 0</pose><mass>0.5</mass><inertia><ixx>0.002</ixx>
    <iyy>0.002</iyy><izz>0.0002</izz></inertia></inertial>
    <collision name="c"><pose>0 0 0.1 0 0 0</pose><geometry><box><size>0.02 0.02 0.2</size>
    </box></geometry></collision></link>
  <joint name="shoulder" type="revolute"><parent>base</parent><child>arm</child>
    <axis><xyz>1 0 0</xyz></axis></joint>
  <link name="wheel"><pose>0 0.3 0.3 0 0 0</pose>
    <inertial><mass>0.2</mass><inertia><ixx>0.001</ixx><iyy>0.001</iyy><izz>0.001</izz>
    </inertia></inertial></link>
  <joint name="spinner" type="continuous"><parent>base</parent><child>wheel</child>
    <axis><xyz>0 1 0</xyz></axis></joint>
  <plugin filename="gz-sim-joint-position-controller-system"
          name="gz::sim::systems::JointPositionController">
    <joint_name>shoulder</joint_name><p_gain>20</p_gain><d_gain>1</d_gain><i_gain>5</i_gain>
  </plugin>
  <plugin filename="gz-sim-joint-controller-system" name="gz::sim::systems::JointController">
    <joint_name>spinner</joint_name>
  </plugin>
  <plugin filename="gz-sim-joint-state-publisher-system"
          name="gz::sim::systems::JointStatePublisher"/>
</model></sdf>"""


def test_joint_controllers_take_float64_commands_on_their_gz_topics(world):
    # gz's /model/arm/joint/shoulder/0/cmd_pos is no ROS name (a token starts with a digit):
    # served under another, as a bridge YAML's ros_topic_name would give it.
    world.world_node.gz_bridge = GzBridge([BridgedTopic(
        '/model/arm/joint/shoulder/0/cmd_pos', 'gz.msgs.Double', '/arm/shoulder_cmd', Float64,
        ROS_TO_GZ)])
    world.spawn_entity('arm', ARM)
    states = world.listener.listen(JointState, '/world/proving_ground/model/arm/joint_state')
    for topic, value in (('/arm/shoulder_cmd', -0.5), ('/model/arm/joint/spinner/cmd_vel', 1.5)):
        publisher = world.listener.create_publisher(Float64, topic, 10)
        assert world.wait_for(lambda: publisher.get_subscription_count() > 0)
        publisher.publish(Float64(data=value))
    world.step(steps(3.0))
    state = states[-1]
    assert list(state.name) == ['shoulder', 'spinner']
    print(f'\narm: shoulder at {state.position[0]:.4f} rad for -0.5, spinner at '
          f'{state.velocity[1]:.4f} rad/s for 1.5')
    assert state.position[0] == pytest.approx(-0.5, abs=0.02)
    assert state.velocity[1] == pytest.approx(1.5, abs=0.01)


def test_an_odometry_publisher_gives_ground_truth_in_its_frames(world):
    text = read_file(SURVEYOR).replace('</model>', """
        <plugin filename="gz-sim-odometry-publisher-system"
                name="gz::sim::systems::OdometryPublisher">
          <odom_topic>truth</odom_topic>
          <odom_frame>world</odom_frame>
          <robot_base_frame>chassis</robot_base_frame>
          <gaussian_noise>0.01</gaussian_noise>
        </plugin>
      </model>""")
    world.spawn_entity('surveyor', text, (1.0, 0.5, 0.0))
    truth = world.listener.listen(Odometry, '/truth')
    covariance = world.listener.listen(Odometry, '/model/surveyor/odometry_with_covariance')
    poses = world.listener.listen(TFMessage, '/model/surveyor/pose')
    world.step(steps(0.5))
    odom = truth[-1]
    assert (odom.header.frame_id, odom.child_frame_id) == ('world', 'chassis')
    assert (odom.pose.pose.position.x, odom.pose.pose.position.y) == pytest.approx(
        (1.0, 0.5), abs=0.005)
    assert odom.pose.covariance[0] == 0.0
    assert covariance[-1].twist.covariance[0] == pytest.approx(0.01 ** 2)
    assert poses[-1].transforms[0].transform.translation.x == pytest.approx(1.0, abs=0.005)


def test_an_rgbd_camera_publishes_colour_depth_points_and_camera_info(world):
    text = read_file(SURVEYOR).replace('type="depth_camera"', 'type="rgbd_camera"').replace(
        '<format>R_FLOAT32</format>', '')
    world.spawn_entity('surveyor', text)
    base = SURVEYOR_SENSORS + 'depth/'
    infos = world.listener.listen(CameraInfo, base + 'camera_info')
    depths = world.listener.listen(Image, base + 'depth_image')
    points = world.listener.listen(PointCloud2, base + 'points')
    image = latest(world, Image, base + 'image')
    assert world.wait_for(lambda: infos and depths and points)
    assert (image.encoding, depths[-1].encoding) == ('rgb8', '32FC1')
    assert infos[-1].header.frame_id == image.header.frame_id == 'surveyor/chassis/depth'
    assert (infos[-1].width, infos[-1].height) == (64, 48)
    depth = np.frombuffer(bytes(depths[-1].data), dtype=np.float32).reshape(48, 64)
    expected = WALL - (world.entity_state('surveyor').pose.position.x + 0.15)
    assert float(depth[24, 32]) == pytest.approx(expected, abs=0.02)
