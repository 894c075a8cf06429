"""
parameter_bridge and image_bridge: a bridge's mappings hold in the world while it runs.

The process is the point (its command line, its life), so each bridge runs as an installed
executable beside a world of its own (SimulatedWorld); what the world serves each gz topic as
is read from its bridge table (node.gz_bridge), which its gz faces make their topics from.
Waits are for events: the table changing, the process ending. With robots spawned (the suite's
burger and surveyor, gz-sim systems and sensors), the world's real topics are read on the graph
and the robots are stepped on simulated time: they drive on the bridged commands and their
sensors publish on the bridged names.
"""

import math
import os
import signal
import subprocess

from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from programs import program_path
import pytest
from rclpy.node import Node
from repository import read_file, TEST_MODELS
from sensor_msgs.msg import CameraInfo, Image, LaserScan
from service_tutorial.testing.simulated_world import SimulatedWorld
from service_tutorial.world_node.bridge_channel import bridge_message, BRIDGES_QOS
from service_tutorial.world_node.bridge_channel import BridgeAnnouncement, BRIDGES_TOPIC
from service_tutorial.world_node.gz_bridge import GZ_TO_ROS, ROS_TO_GZ
from std_msgs.msg import String

# Wall time a bridge may take to start and be heard, or to leave, in s.
EVENT_TIMEOUT = 30.0
CMD_VEL = '/model/burger/cmd_vel'
SCAN = '/world/default/model/burger/link/base_scan/sensor/hls_lfcd_lds/scan'
ODOMETRY = '/model/burger/odometry'
# TurtleBot3's Jazzy bridge file, with gz names as its robot's systems would have them.
BURGER_YAML = f"""\
- ros_topic_name: "clock"
  gz_topic_name: "clock"
  ros_type_name: "rosgraph_msgs/msg/Clock"
  gz_type_name: "gz.msgs.Clock"
  direction: GZ_TO_ROS
- ros_topic_name: "cmd_vel"
  gz_topic_name: "{CMD_VEL}"
  ros_type_name: "geometry_msgs/msg/TwistStamped"
  gz_type_name: "gz.msgs.Twist"
  direction: ROS_TO_GZ
- ros_topic_name: "scan"
  gz_topic_name: "{SCAN}"
  ros_type_name: "sensor_msgs/msg/LaserScan"
  gz_type_name: "gz.msgs.LaserScan"
  direction: GZ_TO_ROS
- ros_topic_name: "camera"
  gz_topic_name: "camera"
  ros_type_name: "sensor_msgs/msg/Image"
  gz_type_name: "gz.msgs.Twist"
"""
BURGER = os.path.join(TEST_MODELS, 'sdf', 'models', 'burger', 'model.sdf')
SURVEYOR = os.path.join(TEST_MODELS, 'sdf', 'models', 'surveyor', 'model.sdf')
SURVEYOR_SENSORS = '/world/empty/model/surveyor/link/chassis/sensor/'
# turtlebot3_simulations' Jazzy bridge file for the burger, less its clock.
TURTLEBOT3_BRIDGE = os.path.join(TEST_MODELS, 'sdf', 'turtlebot3_burger_bridge.yaml')


@pytest.fixture(scope='module')
def world():
    """Start a paused world on simulation time, as launch files start it, for the bridges."""
    simulated = SimulatedWorld(use_sim_time=True, world='empty')
    simulated.user = simulated.add_node(Node('bridge_user', context=simulated.context))
    yield simulated
    simulated.close()


@pytest.fixture
def robot(world):
    """Spawn a robot of the suite into the world, settled on its wheels; delete it after."""
    names = []

    def spawn(name, path):
        world.spawn_entity(name, read_file(path))
        names.append(name)
        world.step(round(0.3 / world.timestep))
    yield spawn
    for name in names:
        world.delete_entity(name)


@pytest.fixture
def start_bridge(world):
    """
    Start bridge programs beside the world: the fixture starts one and returns its Bridge.

    Whatever a test leaves running is killed after it, and the world is seen to drop its
    mappings, so that no test meets another's bridge.
    """
    bridges = []

    def start(program, *args):
        bridges.append(Bridge(world, program, *args))
        return bridges[-1]
    yield start
    for bridge in bridges:
        if bridge.process.poll() is None:
            bridge.process.kill()
            bridge.process.communicate()
    assert world.wait_for(lambda: not world.world_node.gz_bridge.owners, timeout=EVENT_TIMEOUT)


class Bridge:
    """An installed bridge program running beside a world, stopped as launch stops it."""

    def __init__(self, world, program, *args):
        """Start program with args on world's graph."""
        # faulthandler on: a SIGABRT prints where each of its threads is.
        environment = dict(os.environ, ROS_DOMAIN_ID=str(world.domain_id),
                           ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST', PYTHONFAULTHANDLER='1')
        self.program = program
        self.process = subprocess.Popen([program_path(program), *args], env=environment,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True)

    def stop(self):
        """Interrupt it (Ctrl-C, as launch does); return (exit status, what it logged)."""
        self.process.send_signal(signal.SIGINT)
        try:
            out, err = self.process.communicate(timeout=EVENT_TIMEOUT)
        except subprocess.TimeoutExpired:
            self.process.send_signal(signal.SIGABRT)
            out, err = self.process.communicate()
            pytest.fail(f'{self.program} did not end within {EVENT_TIMEOUT:g} s of Ctrl-C; '
                        f'what it logged, and where its threads were:\n{out}{err}')
        return self.process.returncode, out + err


def served(world, gz_name, gz_type, direction):
    """Return (ROS name, ROS type) the world serves a gz topic as, or None."""
    topic = world.world_node.gz_bridge.served(gz_name, gz_type, direction)
    return topic and (topic.ros_name, topic.ros_type)


def wait_served(world, expected, *args):
    """Wait until the world serves a gz topic as expected: (ROS name, ROS type) or None."""
    return world.wait_for(lambda: served(world, *args) == expected, timeout=EVENT_TIMEOUT)


def test_a_yaml_file_maps_the_topics_while_the_bridge_runs_and_the_defaults_come_back(
        world, start_bridge, tmp_path, capfd):
    config = tmp_path / 'turtlebot3_burger_bridge.yaml'
    config.write_text(BURGER_YAML)
    assert served(world, CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ) == (CMD_VEL, Twist)
    bridge = start_bridge('parameter_bridge', '--ros-args', '-p', f'config_file:={config}')
    assert wait_served(world, ('/cmd_vel', TwistStamped), CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ)
    assert served(world, SCAN, 'gz.msgs.LaserScan', GZ_TO_ROS) == ('/scan', LaserScan)
    # Mapped one way, a topic is not served the other.
    assert served(world, CMD_VEL, 'gz.msgs.Twist', GZ_TO_ROS) is None
    status, logged = bridge.stop()
    assert wait_served(world, (CMD_VEL, Twist), CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ)
    assert served(world, SCAN, 'gz.msgs.LaserScan', GZ_TO_ROS) == (SCAN, LaserScan)
    assert status == 0, logged
    # The entry ros_gz_bridge would refuse is named with its file; the others applied.
    assert (f'bridge configuration {config}, entry 4 (camera): sensor_msgs/msg/Image and '
            'gz.msgs.Twist do not go together') in logged
    # The world names, in one warning, what it cannot serve: ros_gz_bridge's Clock.
    warnings = [line for line in capfd.readouterr().err.splitlines()
                if 'does not serve' in line]
    assert len(warnings) == 1 and warnings[0].endswith(
        '[mujoco]: bridge /ros_gz_bridge: 1 of its mappings name types this world does not '
        'serve, left out: /clock (rosgraph_msgs/msg/Clock / gz.msgs.Clock)')


def test_command_line_mappings_resolve_in_the_bridges_namespace_and_go_with_it(
        world, start_bridge):
    bridge = start_bridge('parameter_bridge',
                          f'odom@nav_msgs/msg/Odometry[gz.msgs.Odometry@{ODOMETRY}',
                          f'{CMD_VEL}@geometry_msgs/msg/TwistStamped]gz.msgs.Twist',
                          '--ros-args', '-r', '__ns:=/burger')
    assert wait_served(world, ('/burger/odom', Odometry), ODOMETRY, 'gz.msgs.Odometry',
                       GZ_TO_ROS)
    assert served(world, CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ) == (CMD_VEL, TwistStamped)
    assert world.world_node.gz_bridge.owners == ('/burger/ros_gz_bridge',)
    assert bridge.stop()[0] == 0
    assert wait_served(world, (ODOMETRY, Odometry), ODOMETRY, 'gz.msgs.Odometry', GZ_TO_ROS)
    assert served(world, CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ) == (CMD_VEL, Twist)


def test_expand_gz_topic_names_puts_the_yamls_gz_names_in_the_namespace(
        world, start_bridge, tmp_path):
    config = tmp_path / 'bridge.yaml'
    config.write_text('- topic_name: cmd_vel\n  ros_type_name: geometry_msgs/msg/Twist\n'
                      '  gz_type_name: gz.msgs.Twist\n  direction: ROS_TO_GZ\n')
    bridge = start_bridge('parameter_bridge', '--ros-args', '-r', '__ns:=/robot1',
                          '-p', f'config_file:={config}', '-p', 'expand_gz_topic_names:=true')
    assert wait_served(world, ('/robot1/cmd_vel', Twist), '/robot1/cmd_vel', 'gz.msgs.Twist',
                       ROS_TO_GZ)
    bridge.stop()
    assert wait_served(world, ('/robot1/cmd_vel', Twist), '/robot1/cmd_vel', 'gz.msgs.Twist',
                       GZ_TO_ROS), 'the default, both ways, came back'


def test_image_bridge_serves_each_camera_topic_as_an_image_with_its_camera_info(
        world, start_bridge):
    bridge = start_bridge('image_bridge', '/camera/image_raw')
    assert world.wait_for(lambda: world.world_node.gz_bridge.owners == ('/image_bridge',),
                          timeout=EVENT_TIMEOUT)
    assert served(world, '/camera/image_raw', 'gz.msgs.Image', GZ_TO_ROS) == (
        '/camera/image_raw', Image)
    assert served(world, '/camera/camera_info', 'gz.msgs.CameraInfo', GZ_TO_ROS) == (
        '/camera/camera_info', CameraInfo)
    bridge.stop()
    assert world.wait_for(lambda: not world.world_node.gz_bridge.owners, timeout=EVENT_TIMEOUT)


def test_a_file_refused_whole_is_named_and_the_arguments_still_apply(
        world, start_bridge, tmp_path):
    config = tmp_path / 'broken.yaml'
    config.write_text('- topic_name: [unclosed\n')
    bridge = start_bridge('parameter_bridge', f'{CMD_VEL}@geometry_msgs/msg/Twist]gz.msgs.Twist',
                          '--ros-args', '-p', f'config_file:={config}')
    assert world.wait_for(lambda: world.world_node.gz_bridge.owners == ('/ros_gz_bridge',),
                          timeout=EVENT_TIMEOUT)
    assert served(world, CMD_VEL, 'gz.msgs.Twist', GZ_TO_ROS) is None
    status, logged = bridge.stop()
    assert status == 0 and f'bridge configuration {config}: not YAML at line 2' in logged
    assert world.wait_for(lambda: not world.world_node.gz_bridge.owners, timeout=EVENT_TIMEOUT)


def test_a_bridge_without_mappings_prints_its_usage():
    done = subprocess.run([program_path('parameter_bridge')], capture_output=True, text=True,
                          timeout=EVENT_TIMEOUT)
    assert done.returncode == 255 and 'usage: parameter_bridge' in done.stderr


def test_a_message_that_is_not_a_bridges_mappings_changes_nothing(world):
    node = world.add_node(Node('not_a_bridge', context=world.context))
    publisher = node.create_publisher(String, BRIDGES_TOPIC, BRIDGES_QOS)
    publisher.publish(String(data='- just: [words'))
    publisher.publish(bridge_message('/not_a_bridge', 'no token', []))
    announcement = BridgeAnnouncement(node, [{'topic_name': 'cmd_vel'}])
    assert world.wait_for(lambda: world.world_node.gz_bridge.owners == ('/not_a_bridge',),
                          timeout=EVENT_TIMEOUT)
    # Its one entry lacks the types: nothing of it applies, and it goes when its node goes.
    assert served(world, '/cmd_vel', 'gz.msgs.Twist', ROS_TO_GZ) == ('/cmd_vel', Twist)
    announcement.destroy()
    assert world.wait_for(lambda: not world.world_node.gz_bridge.owners, timeout=EVENT_TIMEOUT)


def world_types(world, topic):
    """Return (types the world publishes on topic, types it subscribes to on it), on the graph."""
    def types(infos):
        return {info.topic_type for info in infos if info.node_name != 'bridge_user'}
    user = world.user
    return (types(user.get_publishers_info_by_topic(topic)),
            types(user.get_subscriptions_info_by_topic(topic)))


def wait_graph(world, expected):
    """Wait until the graph shows the world's {topic: (published types, subscribed types)}."""
    def graph():
        return {topic: world_types(world, topic) for topic in expected}
    assert world.wait_for(lambda: graph() == expected, timeout=EVENT_TIMEOUT), {
        topic: types for topic, types in graph().items() if types != expected[topic]}
    return True


def listen(world, msg_type, topic):
    """Keep what comes on a topic from now on; return the list."""
    received = []
    world.user.create_subscription(msg_type, topic, received.append, 100)
    return received


def drive(world, name, msg_type, topic, seconds=1.0):
    """Command 0.2 m/s on a topic for seconds of simulated time; return the distance driven."""
    publisher = world.user.create_publisher(msg_type, topic, 10)
    assert world.wait_for(lambda: publisher.get_subscription_count() > 0,
                          timeout=EVENT_TIMEOUT), f'nobody takes {topic}'
    start = world.entity_state(name).pose.position
    forward = msg_type()
    (forward.twist if msg_type is TwistStamped else forward).linear.x = 0.2
    publisher.publish(forward)
    world.step(round(seconds / world.timestep))
    publisher.publish(msg_type())
    world.step(round(0.5 / world.timestep))  # it stops
    world.user.destroy_publisher(publisher)
    end = world.entity_state(name).pose.position
    return math.hypot(end.x - start.x, end.y - start.y)


STRING = 'std_msgs/msg/String'
TWIST = 'geometry_msgs/msg/Twist'
TWIST_STAMPED = 'geometry_msgs/msg/TwistStamped'
SCAN_TYPE = 'sensor_msgs/msg/LaserScan'
ODOMETRY_TYPE = 'nav_msgs/msg/Odometry'
TF_TYPE = 'tf2_msgs/msg/TFMessage'
NOTHING = (set(), set())


def test_turtlebot3s_bridge_yaml_renames_and_retypes_the_burgers_real_topics(
        world, start_bridge, robot):
    robot('burger', BURGER)
    # (/tf is the world's own topic too, whichever robot is bridged how.)
    gz_defaults = {'/cmd_vel': (set(), {TWIST}), '/scan': ({SCAN_TYPE}, set()),
                   '/odom': ({ODOMETRY_TYPE}, set())}
    assert wait_graph(world, gz_defaults)
    # Started in a namespace, as a multi-robot launch starts it: the relative ROS names follow.
    bridge = start_bridge('parameter_bridge', '--ros-args', '-r', '__ns:=/tb3',
                          '-p', f'config_file:={TURTLEBOT3_BRIDGE}')
    assert wait_graph(world, {
        '/tb3/cmd_vel': (set(), {TWIST_STAMPED}), '/tb3/scan': ({SCAN_TYPE}, set()),
        '/tb3/odom': ({ODOMETRY_TYPE}, set()), '/tb3/tf': ({TF_TYPE}, set()),
        **{topic: NOTHING for topic in gz_defaults}})
    scans = listen(world, LaserScan, '/tb3/scan')
    odometry = listen(world, Odometry, '/tb3/odom')
    travelled = drive(world, 'burger', TwistStamped, '/tb3/cmd_vel')
    print(f'\nburger: 0.2 m/s on the bridged /tb3/cmd_vel (TwistStamped) for 1 s travelled '
          f'{travelled:.4f} m')
    assert travelled == pytest.approx(0.2 - 0.2 * 0.2 / 2.0, abs=0.01)  # 1 m/s^2 up to speed
    assert scans and len(scans[-1].ranges) == 360 and scans[-1].header.frame_id == 'base_scan'
    assert odometry[-1].pose.pose.position.x == pytest.approx(travelled, abs=0.01)
    status, logged = bridge.stop()
    assert status == 0, logged
    assert wait_graph(world, {**gz_defaults, '/tb3/cmd_vel': NOTHING, '/tb3/scan': NOTHING})
    assert drive(world, 'burger', Twist, '/cmd_vel') > 0.15, 'no drive on the default again'


def test_command_line_mappings_with_remappings_move_the_surveyors_topics(
        world, start_bridge, robot):
    robot('surveyor', SURVEYOR)
    cmd_vel, scan = '/model/surveyor/cmd_vel', SURVEYOR_SENSORS + 'front_lidar/scan'
    # ros_gz's way to give a gz topic another ROS name: the argument names the gz topic, a
    # remapping moves the ROS side.
    bridge = start_bridge('parameter_bridge',
                          f'{cmd_vel}@geometry_msgs/msg/TwistStamped]gz.msgs.Twist',
                          f'{scan}@sensor_msgs/msg/LaserScan[gz.msgs.LaserScan',
                          '--ros-args', '-r', f'{cmd_vel}:=/cmd_vel', '-r', f'{scan}:=/front_scan')
    assert wait_graph(world, {'/cmd_vel': (set(), {TWIST_STAMPED}),
                              '/front_scan': ({SCAN_TYPE}, set()),
                              cmd_vel: NOTHING, scan: NOTHING})
    scans = listen(world, LaserScan, '/front_scan')
    travelled = drive(world, 'surveyor', TwistStamped, '/cmd_vel')
    print(f'\nsurveyor: 0.2 m/s on the bridged /cmd_vel for 1 s travelled {travelled:.4f} m')
    assert 0.19 <= travelled <= 0.21
    assert scans and len(scans[-1].ranges) == 181
    assert bridge.stop()[0] == 0
    assert wait_graph(world, {cmd_vel: (set(), {TWIST}), scan: ({SCAN_TYPE}, set()),
                              '/cmd_vel': NOTHING, '/front_scan': NOTHING})


def test_image_bridge_serves_a_depth_camera_under_the_name_it_is_given(
        world, start_bridge, robot):
    robot('surveyor', SURVEYOR)
    depth = SURVEYOR_SENSORS + 'depth/depth_image'
    bridge = start_bridge('image_bridge', depth, '--ros-args', '-r', f'{depth}:=/depth')
    assert wait_graph(world, {'/depth': ({'sensor_msgs/msg/Image'}, set()), depth: NOTHING})
    images = listen(world, Image, '/depth')
    world.step(round(0.5 / world.timestep))  # the camera runs at 5 Hz
    # It draws in the background: its frame comes once drawn, a tick of the world later.
    assert world.wait_for(lambda: images, timeout=EVENT_TIMEOUT), 'no image on /depth'
    assert (images[-1].width, images[-1].height, images[-1].encoding) == (
        64, 48, '32FC1')
    assert bridge.stop()[0] == 0
    assert wait_graph(world, {depth: ({'sensor_msgs/msg/Image'}, set()), '/depth': NOTHING})
