"""
How the world serves gz topics on ROS: ros_gz_bridge's mapping, in one place.

gz-sim's systems and sensors know their gz topics (sim/plugins/gz_names.py), as gz-sim's do;
ros_gz_bridge decides what ROS sees of each: its ROS name, its ROS type, and the direction it
crosses in. The world is its own bridge, with no relay and no copy: the faces of the gz
plugins (faces/gz_*.py) ask GzBridge.served() for each of their gz topics and make that ROS
topic, or none. With no bridge set up, every gz topic is served under its own name (gz's
names are absolute) with the bridge's default ROS type for its gz type (DEFAULT_ROS_TYPES,
ros_gz_bridge's mappings: Twist for a command), in the direction its system uses it. A bridge
configuration (ros_gz_bridge's YAML, parameter_bridge's arguments) is a set of BridgedTopics
that take the place of the defaults for the gz topics they name: another ROS name, TwistStamped
for Twist, one direction only.
"""

from dataclasses import dataclass

from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, Imu, JointState, LaserScan, NavSatFix
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Bool, Float64
from tf2_msgs.msg import TFMessage

# Which way a gz topic crosses the bridge (ros_gz_bridge's direction).
GZ_TO_ROS = 'GZ_TO_ROS'
ROS_TO_GZ = 'ROS_TO_GZ'
BIDIRECTIONAL = 'BIDIRECTIONAL'
# gz message type -> the ROS type ros_gz_bridge pairs it with when a mapping names none other.
DEFAULT_ROS_TYPES = {
    'gz.msgs.Twist': Twist,
    'gz.msgs.Odometry': Odometry,
    'gz.msgs.OdometryWithCovariance': Odometry,
    'gz.msgs.Pose_V': TFMessage,
    'gz.msgs.Model': JointState,
    'gz.msgs.Double': Float64,
    'gz.msgs.Boolean': Bool,
    'gz.msgs.LaserScan': LaserScan,
    'gz.msgs.PointCloudPacked': PointCloud2,
    'gz.msgs.Image': Image,
    'gz.msgs.CameraInfo': CameraInfo,
    'gz.msgs.IMU': Imu,
    'gz.msgs.NavSat': NavSatFix,
}
# The other ROS types a mapping may pair a gz type with (ros_gz_bridge's factories).
OTHER_ROS_TYPES = {'gz.msgs.Twist': (TwistStamped,)}


@dataclass(frozen=True)
class BridgedTopic:
    """One gz topic as ROS sees it: its ROS name and type, and which way it crosses."""

    gz_name: str
    gz_type: str  # gz.msgs.Twist...
    ros_name: str
    ros_type: type  # the ROS message class, geometry_msgs.msg.Twist...
    direction: str  # GZ_TO_ROS, ROS_TO_GZ or BIDIRECTIONAL

    def carries(self, direction):
        """Tell whether the topic crosses the bridge in a direction (GZ_TO_ROS, ROS_TO_GZ)."""
        return self.direction in (direction, BIDIRECTIONAL)


class GzBridge:
    """The world's bridge: which gz topics ROS sees, under which names and types."""

    def __init__(self, mappings=()):
        """Serve every gz topic by default, or as one of the BridgedTopics in mappings says."""
        self._mappings = {mapping.gz_name: mapping for mapping in mappings}

    def served(self, gz_name, gz_type, direction):
        """
        Return the BridgedTopic a system's gz topic is served as, or None if it is not.

        direction: which way the system needs it: GZ_TO_ROS for what it publishes, ROS_TO_GZ
        for the commands it takes. A mapping of the topic that does not carry it that way
        leaves it unserved, as a bridge set up the other way would.
        """
        mapping = self._mappings.get(gz_name)
        if mapping is None:
            return BridgedTopic(gz_name, gz_type, gz_name, DEFAULT_ROS_TYPES[gz_type],
                                direction)
        return mapping if mapping.carries(direction) else None


def twist_of(msg):
    """Return the geometry_msgs/Twist of a Twist or TwistStamped command."""
    return msg.twist if isinstance(msg, TwistStamped) else msg
