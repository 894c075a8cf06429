"""
ros_gz_bridge's YAML and parameter_bridge's arguments, read as ros_gz_bridge reads them.

The readers (world_node/bridge_config.py) need no ROS; the world's bridge table (gz_bridge.py)
turns what they read into the topics the world serves, and changes as bridges come and go.
"""

from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
import pytest
from sensor_msgs.msg import LaserScan
from service_tutorial.world_node import bridge_config
from service_tutorial.world_node.bridge_config import BIDIRECTIONAL, BridgeConfigError
from service_tutorial.world_node.bridge_config import BridgeEntry, GZ_TO_ROS, parse_argument
from service_tutorial.world_node.bridge_config import read_config_file, read_config_text
from service_tutorial.world_node.bridge_config import ROS_TO_GZ
from service_tutorial.world_node.gz_bridge import bridged_topics, BridgedTopic, GzBridge

# As TurtleBot3's Jazzy bridge files write it (turtlebot3_gazebo/params).
TURTLEBOT3_YAML = """\
# gz topic published by the simulator core
- ros_topic_name: "clock"
  gz_topic_name: "clock"
  ros_type_name: "rosgraph_msgs/msg/Clock"
  gz_type_name: "gz.msgs.Clock"
  direction: GZ_TO_ROS

- ros_topic_name: "cmd_vel"
  gz_topic_name: "cmd_vel"
  ros_type_name: "geometry_msgs/msg/TwistStamped"
  gz_type_name: "gz.msgs.Twist"
  direction: ROS_TO_GZ

- ros_topic_name: "scan"
  gz_topic_name: "scan"
  ros_type_name: "sensor_msgs/msg/LaserScan"
  gz_type_name: "gz.msgs.LaserScan"
  direction: GZ_TO_ROS
"""


def write(tmp_path, text, name='bridge.yaml'):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_turtlebot3s_bridge_file_reads_into_its_mappings(tmp_path):
    reading = read_config_file(write(tmp_path, TURTLEBOT3_YAML))
    assert reading.errors == ()
    clock, cmd_vel, scan = reading.entries
    assert cmd_vel == BridgeEntry('cmd_vel', '/cmd_vel', 'geometry_msgs/msg/TwistStamped',
                                  'gz.msgs.Twist', ROS_TO_GZ)
    assert (scan.ros_name, scan.gz_name, scan.direction) == ('scan', '/scan', GZ_TO_ROS)
    assert clock.ros_type == 'rosgraph_msgs/msg/Clock'


@pytest.mark.parametrize('keys, ros_name, gz_name', [
    ({'topic_name': 'odom'}, 'odom', '/odom'),
    ({'ros_topic_name': '/robot/odom'}, '/robot/odom', '/robot/odom'),
    ({'gz_topic_name': '/model/r/odometry'}, '/model/r/odometry', '/model/r/odometry'),
    ({'ros_topic_name': 'odom', 'gz_topic_name': '/model/r/odometry'}, 'odom',
     '/model/r/odometry'),
])
def test_a_lone_topic_name_names_both_sides(keys, ros_name, gz_name):
    entry = bridge_config.parse_entry({**keys, 'ros_type_name': 'nav_msgs/msg/Odometry',
                                       'gz_type_name': 'gz.msgs.Odometry'})
    assert (entry.ros_name, entry.gz_name) == (ros_name, gz_name)
    assert (entry.direction, entry.publisher_queue, entry.subscriber_queue, entry.lazy) == (
        BIDIRECTIONAL, 10, 10, False)


def test_queues_lazy_and_the_older_spellings_of_types_are_read():
    entry = bridge_config.parse_entry({
        'topic_name': 'cmd_vel', 'ros_type_name': 'geometry_msgs/Twist',
        'gz_type_name': 'ignition.msgs.Twist', 'publisher_queue': 5, 'subscriber_queue': 1,
        'lazy': True})
    assert (entry.ros_type, entry.gz_type) == ('geometry_msgs/msg/Twist', 'gz.msgs.Twist')
    assert (entry.publisher_queue, entry.subscriber_queue, entry.lazy) == (5, 1, True)


def test_gz_names_are_expanded_when_asked_as_expand_gz_topic_names_does():
    reading = read_config_text(
        '- topic_name: cmd_vel\n  ros_type_name: geometry_msgs/msg/Twist\n'
        '  gz_type_name: gz.msgs.Twist\n', source='x.yaml',
        expand_gz=lambda name: '/robot1/' + name)
    (entry,) = reading.entries
    assert (entry.ros_name, entry.gz_name) == ('cmd_vel', '/robot1/cmd_vel')


@pytest.mark.parametrize('text, said', [
    ('- topic_name: [unclosed\n', 'not YAML at line'),
    ('topic_name: cmd_vel\nros_type_name: geometry_msgs/msg/Twist\n', 'not a map'),
    ('just words\n', 'sequence of maps'),
    ('', 'the file is empty'),
    ('# only a comment\n', 'the file is empty'),
])
def test_a_file_that_is_not_a_yaml_sequence_is_refused_naming_the_file(tmp_path, text, said):
    path = write(tmp_path, text)
    with pytest.raises(BridgeConfigError) as refused:
        read_config_file(path)
    assert path in str(refused.value) and said in str(refused.value)


def test_a_100_mb_file_is_refused_by_its_size_before_it_is_read(tmp_path, monkeypatch):
    path = tmp_path / 'huge.yaml'
    with open(path, 'wb') as huge:
        huge.truncate(100 * 1024 * 1024)  # sparse: no disk used

    def not_opened(*args, **kwargs):
        raise AssertionError('the file was opened')
    monkeypatch.setattr(bridge_config, 'open', not_opened, raising=False)
    with pytest.raises(BridgeConfigError, match='104857600 bytes is more than the limit'):
        read_config_file(str(path))


def test_a_missing_file_is_named():
    with pytest.raises(BridgeConfigError, match='/no/such/bridge.yaml: cannot be read'):
        read_config_file('/no/such/bridge.yaml')


BAD_ENTRIES = [
    ({'topic_name': 'camera', 'ros_type_name': 'sensor_msgs/msg/Image',
      'gz_type_name': 'gz.msgs.Twist'},
     'sensor_msgs/msg/Image and gz.msgs.Twist do not go together: gz.msgs.Twist bridges to '
     'geometry_msgs/msg/Twist or geometry_msgs/msg/TwistStamped'),
    ({'topic_name': 'x', 'ros_type_name': 'my_msgs/msg/Thing', 'gz_type_name': 'gz.msgs.Twist'},
     "unknown ROS type 'my_msgs/msg/Thing'"),
    ({'topic_name': 'x', 'ros_type_name': 'geometry_msgs/msg/Twist',
      'gz_type_name': 'gz.msgs.Teleport'}, "unknown gz type 'gz.msgs.Teleport'"),
    ({'topic_name': 'x', 'ros_type_name': 'Twist', 'gz_type_name': 'gz.msgs.Twist'},
     "ROS type 'Twist' is not a message type name"),
    ({'topic_name': 'x', 'ros_type_name': 'geometry_msgs/msg/Twist', 'gz_type_name': 'Twist'},
     "gz type 'Twist' is not a gz message type"),
    ({'ros_topic_name': '2fast/cmd vel', 'gz_topic_name': 'cmd_vel',
      'ros_type_name': 'geometry_msgs/msg/Twist', 'gz_type_name': 'gz.msgs.Twist'},
     "ROS topic '2fast/cmd vel' is not a valid ROS name"),
    ({'ros_topic_name': 'cmd//vel', 'ros_type_name': 'geometry_msgs/msg/Twist',
      'gz_type_name': 'gz.msgs.Twist'}, "ROS topic 'cmd//vel' is not a valid ROS name"),
    ({'ros_topic_name': 'ok', 'gz_topic_name': '@~', 'ros_type_name': 'geometry_msgs/msg/Twist',
      'gz_type_name': 'gz.msgs.Twist'}, "gz topic '@~' is not a valid gz topic name"),
    ({'topic_name': 'x', 'ros_topic_name': 'y', 'ros_type_name': 'geometry_msgs/msg/Twist',
      'gz_type_name': 'gz.msgs.Twist'}, 'topic_name and ros_topic_name are mutually exclusive'),
    ({'topic_name': 'x', 'ros_type_name': 'geometry_msgs/msg/Twist'},
     'both ros_type_name and gz_type_name must be set'),
    ({'topic_name': 'x', 'ros_type_name': 'geometry_msgs/msg/Twist',
      'gz_type_name': 'gz.msgs.Twist', 'direction': 'SIDEWAYS'}, "invalid direction 'SIDEWAYS'"),
    ({'ros_type_name': 'geometry_msgs/msg/Twist', 'gz_type_name': 'gz.msgs.Twist'},
     'no topic'),
    ({'topic_name': 'x', 'ros_type_name': 'geometry_msgs/msg/Twist',
      'gz_type_name': 'gz.msgs.Twist', 'publisher_queue': -1}, 'publisher_queue must be'),
    ({'topic_name': 'x', 'ros_type_name': 'geometry_msgs/msg/Twist',
      'gz_type_name': 'gz.msgs.Twist', 'lazy': 'sometimes'}, 'lazy must be true or false'),
]


@pytest.mark.parametrize('entry, said', BAD_ENTRIES)
def test_a_bad_entry_is_named_with_its_file_and_the_others_still_apply(tmp_path, entry, said):
    import yaml
    good = {'topic_name': 'odom', 'ros_type_name': 'nav_msgs/msg/Odometry',
            'gz_type_name': 'gz.msgs.Odometry'}
    path = write(tmp_path, yaml.safe_dump([good, entry, good]))
    reading = read_config_file(path)
    assert [entry.ros_name for entry in reading.entries] == ['odom', 'odom']
    (error,) = reading.errors
    assert error.startswith(f'bridge configuration {path}, entry 2')
    assert said in error


def test_an_entry_that_is_not_a_map_is_named_by_its_place(tmp_path):
    reading = read_config_text('- just a word\n', source='b.yaml')
    assert reading.errors == ('bridge configuration b.yaml, entry 1: an entry must be a YAML '
                              "map, not a str ('just a word')",)


@pytest.mark.parametrize('argument, entry', [
    ('/cmd_vel@geometry_msgs/msg/Twist@gz.msgs.Twist',
     BridgeEntry('/cmd_vel', '/cmd_vel', 'geometry_msgs/msg/Twist', 'gz.msgs.Twist')),
    ('/scan@sensor_msgs/msg/LaserScan[gz.msgs.LaserScan',
     BridgeEntry('/scan', '/scan', 'sensor_msgs/msg/LaserScan', 'gz.msgs.LaserScan', GZ_TO_ROS)),
    ('cmd_vel@geometry_msgs/msg/TwistStamped]ignition.msgs.Twist',
     BridgeEntry('cmd_vel', '/cmd_vel', 'geometry_msgs/msg/TwistStamped', 'gz.msgs.Twist',
                 ROS_TO_GZ)),
    ('/ros/odom@nav_msgs/msg/Odometry[gz.msgs.Odometry@/model/r/odometry',
     BridgeEntry('/ros/odom', '/model/r/odometry', 'nav_msgs/msg/Odometry', 'gz.msgs.Odometry',
                 GZ_TO_ROS)),
])
def test_parameter_bridge_arguments_read_as_its_own(argument, entry):
    assert parse_argument(argument) == entry


@pytest.mark.parametrize('argument, said', [
    ('/cmd_vel', 'is not topic@ros_type@gz_type'),
    ('@geometry_msgs/msg/Twist@gz.msgs.Twist', 'is not topic@ros_type@gz_type'),
    ('/cmd_vel@geometry_msgs/msg/Twist', 'has no gz type'),
    ('/cmd_vel@geometry_msgs/msg/Twist@', 'has no gz type'),
    ('/camera@sensor_msgs/msg/Image[gz.msgs.Twist', 'do not go together'),
    ('/world/default/control@ros_gz_interfaces/srv/ControlWorld', 'bridges a service'),
])
def test_a_bad_argument_is_refused_naming_it(argument, said):
    with pytest.raises(BridgeConfigError, match=said):
        parse_argument(argument)


# --- the world's bridge table -----------------------------------------------------------------

def test_entries_become_the_topics_the_world_serves_and_the_rest_are_named():
    reading = read_config_text(TURTLEBOT3_YAML, source='tb3.yaml')
    topics, unserved = bridged_topics(reading.entries, resolve=lambda name: '/tb3/' + name)
    assert topics == [
        BridgedTopic('/cmd_vel', 'gz.msgs.Twist', '/tb3/cmd_vel', TwistStamped, ROS_TO_GZ),
        BridgedTopic('/scan', 'gz.msgs.LaserScan', '/tb3/scan', LaserScan, GZ_TO_ROS)]
    assert unserved == ['/clock (rosgraph_msgs/msg/Clock / gz.msgs.Clock)']


def test_the_bridge_serves_the_defaults_until_a_bridge_maps_a_topic_and_after_it_goes():
    bridge = GzBridge()
    changes = []
    bridge.on_change(lambda: changes.append(bridge.owners))
    default = bridge.served('/model/r/cmd_vel', 'gz.msgs.Twist', ROS_TO_GZ)
    assert (default.ros_name, default.ros_type) == ('/model/r/cmd_vel', Twist)
    stamped = BridgedTopic('/model/r/cmd_vel', 'gz.msgs.Twist', '/cmd_vel', TwistStamped,
                           ROS_TO_GZ)
    bridge.set_mappings('a', [stamped])
    assert bridge.served('/model/r/cmd_vel', 'gz.msgs.Twist', ROS_TO_GZ) == stamped
    # A bridge set up one way leaves the other unserved.
    assert bridge.served('/model/r/cmd_vel', 'gz.msgs.Twist', GZ_TO_ROS) is None
    odometry = BridgedTopic('/model/r/odometry', 'gz.msgs.OdometryWithCovariance', '/odom',
                            Odometry, GZ_TO_ROS)
    bridge.set_mappings('c', [odometry])
    # A mapping of another gz type than the system publishes carries nothing, as in gz.
    assert bridge.served('/model/r/odometry', 'gz.msgs.Odometry', GZ_TO_ROS) is None
    assert bridge.served('/model/r/odometry', 'gz.msgs.OdometryWithCovariance', GZ_TO_ROS) == \
        odometry
    bridge.drop('c')
    plain = BridgedTopic('/model/r/cmd_vel', 'gz.msgs.Twist', '/b/cmd_vel', Twist, BIDIRECTIONAL)
    bridge.set_mappings('b', [plain])
    assert bridge.served('/model/r/cmd_vel', 'gz.msgs.Twist', ROS_TO_GZ) == plain
    assert bridge.drop('b') and not bridge.drop('b')
    assert bridge.served('/model/r/cmd_vel', 'gz.msgs.Twist', ROS_TO_GZ) == stamped
    bridge.drop('a')
    assert bridge.served('/model/r/cmd_vel', 'gz.msgs.Twist', ROS_TO_GZ) == default
    assert changes == [('a',), ('a', 'c'), ('a',), ('a', 'b'), ('a',), ()]
