"""
A gz lidar's face: sensor_msgs/LaserScan, and PointCloud2 for a scan of several rows.

The scan is the middle row, as ros_gz_bridge turns gz's LaserScan into a ROS one; the points
(x, y, z, intensity as float32, ring as uint16; intensity 0) are every row's, in the sensor
frame, an organised cloud of rows by beams.
"""

import array

import numpy as np
from sensor_msgs.msg import LaserScan, PointCloud2, PointField
from service_tutorial.conversions import fill_time_msg
from service_tutorial.sim.plugins.gz_lidar import GzLidar
from service_tutorial.world_node.faces.gz_sensor import data_of, GzSensorFace

POINT_FIELDS = [PointField(name=name, offset=4 * index, datatype=PointField.FLOAT32, count=1)
                for index, name in enumerate(('x', 'y', 'z', 'intensity'))] + \
    [PointField(name='ring', offset=16, datatype=PointField.UINT16, count=1)]
POINT = np.dtype({'names': ['x', 'y', 'z', 'intensity', 'ring'],
                  'formats': ['<f4', '<f4', '<f4', '<f4', '<u2'],
                  'offsets': [0, 4, 8, 12, 16], 'itemsize': 18})


class GzLidarFace(GzSensorFace, sensor_type=GzLidar):
    """A gz lidar's scan, and points for a scan of several rows."""

    gz_types = {'scan': 'gz.msgs.LaserScan', 'points': 'gz.msgs.PointCloudPacked'}

    def make_topics(self):
        """Make the topics and fill in what every message shares."""
        config = self.sensor.config
        msg = self.scan_msg = LaserScan()
        msg.header.frame_id = self.frame
        msg.angle_min, msg.angle_max = config.angle_min, config.angle_max
        msg.angle_increment = config.angle_increment
        msg.scan_time = self.sensor.period if self.sensor.world is not None else 0.0
        msg.range_min, msg.range_max = config.range_min, config.range_max
        self.scan_pub = self.publisher('scan')
        cloud = self.cloud_msg = PointCloud2()
        cloud.header.frame_id = self.frame
        cloud.height, cloud.width = config.vertical_samples, config.horizontal_samples
        cloud.fields, cloud.point_step = POINT_FIELDS, POINT.itemsize
        cloud.row_step = POINT.itemsize * config.horizontal_samples
        self.points_pub = self.publisher('points')
        self.rings = np.repeat(np.arange(config.vertical_samples, dtype=np.uint16),
                               config.horizontal_samples)

    def publish_reading(self, sensor):
        """Publish the scan the lidar just made, and its points."""
        if self.scan_pub is not None:
            msg = self.scan_msg
            fill_time_msg(msg.header.stamp, sensor.reading_time)
            msg.ranges = array.array('f', sensor.middle_row().tobytes())
            self.scan_pub.publish(msg)
        if self.points_pub is not None and self.points_pub.get_subscription_count() > 0:
            cloud = self.cloud_msg
            fill_time_msg(cloud.header.stamp, sensor.reading_time)
            points = np.zeros(len(self.rings), dtype=POINT)
            xyz = sensor.points()
            points['x'], points['y'], points['z'] = xyz[:, 0], xyz[:, 1], xyz[:, 2]
            points['ring'] = self.rings
            cloud.data = data_of(points)
            cloud.is_dense = bool(np.isfinite(xyz).all())
            self.points_pub.publish(cloud)
