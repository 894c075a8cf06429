"""tf2_msgs is there, from the system's Jazzy or built by scripts/setup for the wheels."""

from ament_index_python.packages import get_package_share_directory
from geometry_msgs.msg import TransformStamped
import pytest
from rclpy.qos import DurabilityPolicy, QoSProfile
from tf2_msgs.msg import TFMessage

pytestmark = pytest.mark.ros


def test_tfmessage_is_a_list_of_stamped_transforms():
    assert TFMessage.get_fields_and_field_types() == {
        'transforms': 'sequence<geometry_msgs/TransformStamped>'}
    assert get_package_share_directory('tf2_msgs')


def transform(parent, child, x, yaw_sin, yaw_cos, sec):
    msg = TransformStamped()
    msg.header.frame_id, msg.child_frame_id = parent, child
    msg.header.stamp.sec, msg.header.stamp.nanosec = sec, 250_000_000
    msg.transform.translation.x = x
    msg.transform.rotation.z, msg.transform.rotation.w = yaw_sin, yaw_cos
    return msg


def test_a_tfmessage_round_trips_through_a_publisher_and_a_subscriber(ros):
    qos = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
    publisher = ros.client_node.create_publisher(TFMessage, 'tf2_msgs_round_trip', qos)
    sent = TFMessage(transforms=[transform('odom', 'base_footprint', 1.5, 0.6, 0.8, 7),
                                 transform('base_footprint', 'base_link', 0.0, 0.0, 1.0, 7)])
    publisher.publish(sent)  # transient local: a subscriber that comes later still gets it
    received = []
    ros.client_node.create_subscription(TFMessage, 'tf2_msgs_round_trip', received.append, qos)
    assert ros.wait_for(lambda: received), 'no TFMessage arrived'
    assert received[0] == sent
