"""
An IMU's face (gazebo_ros_imu, ROS 1; gazebo_ros_imu_sensor, ROS 2): sensor_msgs/Imu.

The covariances follow from the sensor's noise; ROS 1's plugin publishes on /default_imu
without a topicName, ROS 2's on ~/out.
"""

from sensor_msgs.msg import Imu
from service_tutorial.conversions import fill_quaternion_msg, fill_time_msg
from service_tutorial.sim.plugins.imu_sensor import ImuSensor
from service_tutorial.sim.plugins.imu_sensor import is_ros1_block as is_ros1_imu
from service_tutorial.world_node.faces.sensor import diagonal, sensor_frame, SensorFace
from service_tutorial.world_node.ros_names import plugin_topic


class ImuFace(SensorFace, sensor_type=ImuSensor):
    """An IMU's sensor_msgs/Imu (gazebo_ros_imu, ROS 1; gazebo_ros_imu_sensor, ROS 2)."""

    def __init__(self, node, world, model, plugin, namespace):
        """Name the topic and the frame of the IMU's readings."""
        super().__init__(node, world, model, plugin, namespace)
        sensor = plugin
        block = sensor.block
        ros1 = is_ros1_imu(block)
        if ros1:
            topic = plugin_topic(block, '/default_imu', robot_namespace=namespace,
                                 ros1_tag='topicName')
        else:
            topic = plugin_topic(block, '~/out', robot_namespace=namespace)
        self.frame = sensor_frame(block, ros1, sensor)
        self.topics = (topic,)
        self.imu_pub = self.imu_msg = None

    def make_topics(self):
        """Make the IMU's topic and fill in the covariances, which follow from the noise."""
        sensor = self.sensor
        msg = self.imu_msg = Imu()
        msg.header.frame_id = self.frame
        msg.orientation_covariance = diagonal(sensor.covariance('orientation'))
        msg.angular_velocity_covariance = diagonal(sensor.covariance('angular_velocity'))
        msg.linear_acceleration_covariance = diagonal(
            sensor.covariance('linear_acceleration'))
        self.imu_pub = self.publisher(Imu, self.topics[0], 10)

    def publish_reading(self, sensor):
        """Publish the IMU's latest reading."""
        msg = self.imu_msg
        fill_time_msg(msg.header.stamp, sensor.reading_time)
        fill_quaternion_msg(msg.orientation, sensor.orientation)
        for vector, values in ((msg.angular_velocity, sensor.angular_velocity),
                               (msg.linear_acceleration, sensor.linear_acceleration)):
            vector.x, vector.y, vector.z = (float(value) for value in values)
        self.imu_pub.publish(msg)
