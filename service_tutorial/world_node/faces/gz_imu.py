"""A gz IMU's face: sensor_msgs/Imu, its covariances the variances of its noise."""

from sensor_msgs.msg import Imu
from service_tutorial.conversions import fill_quaternion_msg, fill_time_msg
from service_tutorial.sim.plugins.gz_imu import GzImu
from service_tutorial.world_node.faces.gz_sensor import GzSensorFace
from service_tutorial.world_node.faces.sensor import diagonal


class GzImuFace(GzSensorFace, sensor_type=GzImu):
    """A gz IMU's readings."""

    gz_types = {'imu': 'gz.msgs.IMU'}

    def make_topics(self):
        """Make the topic and fill in the covariances, which follow from the noise."""
        sensor = self.sensor
        msg = self.imu_msg = Imu()
        msg.header.frame_id = self.frame
        if sensor.config.enable_orientation:
            msg.orientation_covariance = diagonal(sensor.covariance('orientation'))
        else:
            msg.orientation_covariance = [-1.0] + [0.0] * 8  # REP 145: no orientation
        msg.angular_velocity_covariance = diagonal(sensor.covariance('angular_velocity'))
        msg.linear_acceleration_covariance = diagonal(
            sensor.covariance('linear_acceleration'))
        self.imu_pub = self.publisher('imu')

    def publish_reading(self, sensor):
        """Publish the IMU's latest reading."""
        if self.imu_pub is None:
            return
        msg = self.imu_msg
        fill_time_msg(msg.header.stamp, sensor.reading_time)
        if sensor.config.enable_orientation:
            fill_quaternion_msg(msg.orientation, sensor.orientation)
        for vector, values in ((msg.angular_velocity, sensor.angular_velocity),
                               (msg.linear_acceleration, sensor.linear_acceleration)):
            vector.x, vector.y, vector.z = (float(value) for value in values)
        self.imu_pub.publish(msg)
