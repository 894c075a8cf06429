"""
A laser's face (gazebo_ros_laser, ROS 1; gazebo_ros_ray_sensor, ROS 2): sensor_msgs/LaserScan.

Without a topicName, ROS 1's plugin publishes on /world (sic); ROS 2's on ~/out, remapped as
its block says. Only LaserScan is simulated, whatever output_type asks for.
"""

import array

from sensor_msgs.msg import LaserScan
from service_tutorial.conversions import fill_time_msg
from service_tutorial.sim.plugins.ray_sensor import RaySensor
from service_tutorial.sim.validation import quoted
from service_tutorial.world_node.faces.sensor import sensor_frame, SensorFace
from service_tutorial.world_node.ros_names import plugin_topic

# The one type a laser publishes here; gazebo_ros_ray_sensor can also give point clouds.
LASER_SCAN_TYPE = 'sensor_msgs/LaserScan'


class LaserScanFace(SensorFace, sensor_type=RaySensor):
    """A laser's sensor_msgs/LaserScan (gazebo_ros_laser, gazebo_ros_ray_sensor)."""

    def __init__(self, node, world, model, plugin, namespace):
        """Name the scan topic and the frame every scan of this laser names."""
        super().__init__(node, world, model, plugin, namespace)
        sensor = plugin
        block = sensor.block
        ros1 = 'gazebo_ros_laser' in block.filename
        if ros1:
            # Without a topicName, gazebo_ros_laser publishes on /world (sic).
            topic = plugin_topic(block, '/world', robot_namespace=namespace,
                                 ros1_tag='topicName')
        else:
            topic = plugin_topic(block, '~/out', robot_namespace=namespace)
            output_type = block.text('output_type', LASER_SCAN_TYPE)
            if output_type.replace('/msg/', '/') != LASER_SCAN_TYPE:
                node.get_logger().warning(
                    f'laser {quoted(block.name)} asks for {quoted(output_type)}; only '
                    f'{LASER_SCAN_TYPE} is simulated, on {topic}')
        self.frame = sensor_frame(block, ros1, sensor)
        self.topics = (topic,)
        self.scan_pub = self.scan_msg = None

    def make_topics(self):
        """Make the scan topic and fill in what every scan of this laser shares."""
        config = self.sensor.config
        msg = self.scan_msg = LaserScan()
        msg.header.frame_id = self.frame
        msg.angle_min, msg.angle_max = config.angle_min, config.angle_max
        msg.angle_increment = config.angle_increment
        msg.time_increment = 0.0  # every beam of a scan is cast at the same instant
        msg.scan_time = self.sensor.period
        msg.range_min, msg.range_max = config.range_min, config.range_max
        self.scan_pub = self.publisher(LaserScan, self.topics[0], 10)

    def publish_reading(self, sensor):
        """Publish the scan the laser just made."""
        msg = self.scan_msg
        fill_time_msg(msg.header.stamp, sensor.reading_time)
        msg.ranges = array.array('f', sensor.ranges.tobytes())
        self.scan_pub.publish(msg)
