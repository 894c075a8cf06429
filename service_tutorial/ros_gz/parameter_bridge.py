"""
ros_gz_bridge's parameter_bridge, for this world: its command line, and no relay.

    ros2 run service_tutorial parameter_bridge /scan@sensor_msgs/msg/LaserScan[gz.msgs.LaserScan
    ros2 run service_tutorial parameter_bridge --ros-args -p config_file:=bridge.yaml

The same arguments as ros_gz_bridge's (topic@ros_type@gz_type, with '[' or ']' for one
direction, bridge_config.py) and parameters (config_file, expand_gz_topic_names, which expands
the YAML's gz names as ROS names of this node), so that a Gazebo launch file runs with its
package changed. The world serves bridged topics itself: this process only tells it its
mappings, with every ROS name resolved as this node would resolve it (namespace, remappings),
on the world's bridge channel (world_node/bridge_channel.py), and the world applies them for as
long as this process runs. A mapping that ros_gz_bridge would refuse is named on stderr and left
out; the others apply.
"""

import sys

from rclpy.expand_topic_name import expand_topic_name
from rclpy.node import Node
from service_tutorial.node_main import program_arguments, spin_node
from service_tutorial.world_node.bridge_channel import BridgeAnnouncement
from service_tutorial.world_node.bridge_config import BridgeConfigError, parse_argument
from service_tutorial.world_node.bridge_config import read_config_file

USAGE = """usage: parameter_bridge [topic@ros_type@gz_type ...] [--ros-args -p config_file:=FILE]

Serve gz topics of the world on ROS as ros_gz_bridge would, for as long as this runs.
The delimiter after the ROS type: @ both ways, [ from gz to ROS, ] from ROS to gz;
topic@ros_type@gz_type@gz_topic names the gz side apart.
Parameters: config_file (ros_gz_bridge's YAML), expand_gz_topic_names (false)."""


class ParameterBridge(Node):
    """A bridge of the world: its mappings, told to the world, apply while it runs."""

    def __init__(self, mappings_of, *, node_name='ros_gz_bridge'):
        """
        Tell the world the mappings mappings_of(node) returns as (BridgeEntries, errors).

        The errors (bad entries or a file refused, left out) are logged.
        """
        super().__init__(node_name)
        entries, errors = mappings_of(self)
        for error in errors:
            self.get_logger().error(error)
        self.mappings = [self.resolved(entry) for entry in entries]
        for mapping in self.mappings:
            self.get_logger().info(
                f'bridging {mapping["gz_topic_name"]} ({mapping["gz_type_name"]}) and '
                f'{mapping["ros_topic_name"]} ({mapping["ros_type_name"]}), '
                f'{mapping["direction"]}')
        self.announcement = BridgeAnnouncement(self, self.mappings)

    def resolved(self, entry):
        """Return an entry as YAML keys with its ROS name as this node resolves it."""
        mapping = entry.as_yaml_entry()
        mapping['ros_topic_name'] = self.resolve_topic_name(entry.ros_name)
        return mapping

    def expand_gz_name(self, name):
        """Expand a gz topic name of the YAML file as a ROS name of this node."""
        return expand_topic_name(name, self.get_name(), self.get_namespace())


def parameter_bridge_mappings(arguments):
    """Return mappings_of(node) for ParameterBridge: the arguments', then config_file's."""
    def mappings_of(node):
        entries, errors = [], []
        for argument in arguments:
            try:
                entries.append(parse_argument(argument))
            except BridgeConfigError as error:
                errors.append(str(error))
        config_file = node.declare_parameter('config_file', '').value
        expand = node.declare_parameter('expand_gz_topic_names', False).value
        if config_file:
            try:
                reading = read_config_file(
                    config_file, expand_gz=node.expand_gz_name if expand else None)
                entries += reading.entries
                errors += reading.errors
            except BridgeConfigError as error:  # the arguments' mappings still apply
                errors.append(str(error))
        return entries, errors
    return mappings_of


def main(args=None):
    """Run the bridge until Ctrl-C; without any mapping, print the usage (status 255)."""
    arguments = program_arguments(args)
    if not arguments and '--ros-args' not in (sys.argv if args is None else args):
        print(USAGE, file=sys.stderr)
        return 255
    return spin_node(lambda: ParameterBridge(parameter_bridge_mappings(arguments)), args=args)


if __name__ == '__main__':
    sys.exit(main())
