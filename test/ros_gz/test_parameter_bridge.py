"""
parameter_bridge and image_bridge: a bridge's mappings hold in the world while it runs.

The process is the point (its command line, its life), so each bridge runs as an installed
executable beside a world of its own (SimulatedWorld); what the world serves each gz topic as
is read from its bridge table (node.gz_bridge), which its gz faces make their topics from.
Waits are for events: the table changing, the process ending.
"""

import os
import signal
import subprocess

from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from programs import program_path
import pytest
from rclpy.node import Node
from sensor_msgs.msg import CameraInfo, Image, LaserScan
from service_tutorial.testing.simulated_world import SimulatedWorld
from service_tutorial.world_node.bridge_channel import bridge_message, BRIDGES_QOS
from service_tutorial.world_node.bridge_channel import BRIDGES_TOPIC
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


@pytest.fixture(scope='module')
def world():
    """Start a paused world on simulation time, as launch files start it, for the bridges."""
    simulated = SimulatedWorld(use_sim_time=True)
    yield simulated
    simulated.close()


class Bridge:
    """An installed bridge program running beside a world, stopped as launch stops it."""

    def __init__(self, world, program, *args):
        """Start program with args on world's graph."""
        environment = dict(os.environ, ROS_DOMAIN_ID=str(world.domain_id),
                           ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
        self.process = subprocess.Popen([program_path(program), *args], env=environment,
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True)

    def stop(self):
        """Interrupt it (Ctrl-C, as launch does); return (exit status, what it logged)."""
        self.process.send_signal(signal.SIGINT)
        out, err = self.process.communicate(timeout=EVENT_TIMEOUT)
        return self.process.returncode, out + err


def served(world, gz_name, gz_type, direction):
    """Return (ROS name, ROS type) the world serves a gz topic as, or None."""
    topic = world.world_node.gz_bridge.served(gz_name, gz_type, direction)
    return topic and (topic.ros_name, topic.ros_type)


def wait_served(world, expected, *args):
    """Wait until the world serves a gz topic as expected: (ROS name, ROS type) or None."""
    return world.wait_for(lambda: served(world, *args) == expected, timeout=EVENT_TIMEOUT)


def test_a_yaml_file_maps_the_topics_while_the_bridge_runs_and_the_defaults_come_back(
        world, tmp_path, capfd):
    config = tmp_path / 'turtlebot3_burger_bridge.yaml'
    config.write_text(BURGER_YAML)
    assert served(world, CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ) == (CMD_VEL, Twist)
    bridge = Bridge(world, 'parameter_bridge', '--ros-args', '-p', f'config_file:={config}')
    assert wait_served(world, ('/cmd_vel', TwistStamped), CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ)
    assert served(world, SCAN, 'gz.msgs.LaserScan', GZ_TO_ROS) == ('/scan', LaserScan)
    # Mapped one way, a topic is not served the other.
    assert served(world, CMD_VEL, 'gz.msgs.Twist', GZ_TO_ROS) is None
    status, logged = bridge.stop()
    assert wait_served(world, (CMD_VEL, Twist), CMD_VEL, 'gz.msgs.Twist', ROS_TO_GZ)
    assert served(world, SCAN, 'gz.msgs.LaserScan', GZ_TO_ROS) == (SCAN, LaserScan)
    assert status == 0
    # The entry ros_gz_bridge would refuse is named with its file; the others applied.
    assert (f'bridge configuration {config}, entry 4 (camera): sensor_msgs/msg/Image and '
            'gz.msgs.Twist do not go together') in logged
    # The world names, in one warning, what it cannot serve: ros_gz_bridge's Clock.
    warnings = [line for line in capfd.readouterr().err.splitlines()
                if 'does not serve' in line]
    assert len(warnings) == 1 and warnings[0].endswith(
        '[mujoco]: bridge /ros_gz_bridge: 1 of its mappings name types this world does not '
        'serve, left out: /clock (rosgraph_msgs/msg/Clock / gz.msgs.Clock)')


def test_command_line_mappings_resolve_in_the_bridges_namespace_and_go_with_it(world):
    bridge = Bridge(world, 'parameter_bridge',
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


def test_expand_gz_topic_names_puts_the_yamls_gz_names_in_the_namespace(world, tmp_path):
    config = tmp_path / 'bridge.yaml'
    config.write_text('- topic_name: cmd_vel\n  ros_type_name: geometry_msgs/msg/Twist\n'
                      '  gz_type_name: gz.msgs.Twist\n  direction: ROS_TO_GZ\n')
    bridge = Bridge(world, 'parameter_bridge', '--ros-args', '-r', '__ns:=/robot1',
                    '-p', f'config_file:={config}', '-p', 'expand_gz_topic_names:=true')
    assert wait_served(world, ('/robot1/cmd_vel', Twist), '/robot1/cmd_vel', 'gz.msgs.Twist',
                       ROS_TO_GZ)
    bridge.stop()
    assert wait_served(world, ('/robot1/cmd_vel', Twist), '/robot1/cmd_vel', 'gz.msgs.Twist',
                       GZ_TO_ROS), 'the default, both ways, came back'


def test_image_bridge_serves_each_camera_topic_as_an_image_with_its_camera_info(world):
    bridge = Bridge(world, 'image_bridge', '/camera/image_raw')
    assert world.wait_for(lambda: world.world_node.gz_bridge.owners == ('/image_bridge',),
                          timeout=EVENT_TIMEOUT)
    assert served(world, '/camera/image_raw', 'gz.msgs.Image', GZ_TO_ROS) == (
        '/camera/image_raw', Image)
    assert served(world, '/camera/camera_info', 'gz.msgs.CameraInfo', GZ_TO_ROS) == (
        '/camera/camera_info', CameraInfo)
    bridge.stop()
    assert world.wait_for(lambda: not world.world_node.gz_bridge.owners, timeout=EVENT_TIMEOUT)


def test_a_file_refused_whole_is_named_and_the_arguments_still_apply(world, tmp_path):
    config = tmp_path / 'broken.yaml'
    config.write_text('- topic_name: [unclosed\n')
    bridge = Bridge(world, 'parameter_bridge', f'{CMD_VEL}@geometry_msgs/msg/Twist]gz.msgs.Twist',
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
    publisher.publish(bridge_message('/not_a_bridge', [{'topic_name': 'cmd_vel'}]))
    assert world.wait_for(lambda: world.world_node.gz_bridge.owners == ('/not_a_bridge',),
                          timeout=EVENT_TIMEOUT)
    # Its one entry lacks the types: nothing of it applies, and it goes when its node goes.
    assert served(world, '/cmd_vel', 'gz.msgs.Twist', ROS_TO_GZ) == ('/cmd_vel', Twist)
    node.destroy_publisher(publisher)
    assert world.wait_for(lambda: not world.world_node.gz_bridge.owners, timeout=EVENT_TIMEOUT)
