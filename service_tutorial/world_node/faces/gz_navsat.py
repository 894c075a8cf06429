"""
A gz NavSat's face: sensor_msgs/NavSatFix, as ros_gz_bridge has it.

Status FIX by GPS, latitude and longitude in degrees, altitude in m, covariance UNKNOWN; the
velocity gz measures is not in a NavSatFix.
"""

from sensor_msgs.msg import NavSatFix, NavSatStatus
from service_tutorial.conversions import fill_time_msg
from service_tutorial.sim.plugins.gz_navsat import GzNavSat
from service_tutorial.world_node.faces.gz_sensor import GzSensorFace


class GzNavSatFace(GzSensorFace, sensor_type=GzNavSat):
    """A gz NavSat's fixes."""

    gz_types = {'navsat': 'gz.msgs.NavSat'}

    def make_topics(self):
        """Make the topic and fill in what every fix shares."""
        msg = self.fix_msg = NavSatFix()
        msg.header.frame_id = self.frame
        msg.status.status = NavSatStatus.STATUS_FIX
        msg.status.service = NavSatStatus.SERVICE_GPS
        msg.position_covariance_type = NavSatFix.COVARIANCE_TYPE_UNKNOWN
        self.fix_pub = self.publisher('navsat')

    def publish_reading(self, sensor):
        """Publish the latest fix."""
        if self.fix_pub is None:
            return
        msg = self.fix_msg
        fill_time_msg(msg.header.stamp, sensor.reading_time)
        msg.latitude, msg.longitude = float(sensor.latitude), float(sensor.longitude)
        msg.altitude = float(sensor.altitude)
        self.fix_pub.publish(msg)
