"""
A gz camera's face: Image, depth Image (32FC1), PointCloud2 and CameraInfo, as it has them.

A camera publishes its image and camera_info; a depth camera its depth image, points and
camera_info; an RGBD camera all four. The points (x, y, z as float32) form an organised cloud
of the depth image's rows and columns, in the sensor frame. CameraInfo is the Classic
camera's: a pinhole without distortion.
"""

import numpy as np
from sensor_msgs.msg import Image, PointCloud2, PointField
from service_tutorial.conversions import fill_time_msg
from service_tutorial.sim.plugins.gz_camera import DEPTH_ENCODING, GzCamera
from service_tutorial.world_node.faces.camera import camera_info
from service_tutorial.world_node.faces.gz_sensor import data_of, GzSensorFace

POINT_FIELDS = [PointField(name=name, offset=4 * index, datatype=PointField.FLOAT32, count=1)
                for index, name in enumerate(('x', 'y', 'z'))]


class GzCameraFace(GzSensorFace, sensor_type=GzCamera):
    """A gz camera's images, points and camera_info."""

    gz_types = {'image': 'gz.msgs.Image', 'depth_image': 'gz.msgs.Image',
                'points': 'gz.msgs.PointCloudPacked', 'camera_info': 'gz.msgs.CameraInfo'}

    def make_topics(self):
        """Make the topics and describe the camera once."""
        config = self.sensor.config
        self.image_msg, self.depth_msg, self.cloud_msg = Image(), Image(), PointCloud2()
        for msg in (self.image_msg, self.depth_msg, self.cloud_msg):
            msg.header.frame_id = self.frame
            msg.height, msg.width = config.height, config.width
        self.image_msg.encoding = config.encoding
        self.image_msg.step = config.width * (1 if config.encoding == 'mono8' else 3)
        self.depth_msg.encoding, self.depth_msg.step = DEPTH_ENCODING, 4 * config.width
        self.cloud_msg.fields, self.cloud_msg.point_step = POINT_FIELDS, 12
        self.cloud_msg.row_step = 12 * config.width
        self.info_msg = camera_info(config, self.frame)
        self.pubs = {role: self.publisher(role) for role in self.gz_types}

    def publish_reading(self, sensor):
        """Publish what the camera just drew, on each topic someone listens to."""
        stamp = sensor.reading_time
        wanted = {role: publisher for role, publisher in self.pubs.items()
                  if publisher is not None and publisher.get_subscription_count() > 0}
        for role, msg, pixels in (('image', self.image_msg, sensor.image),
                                  ('depth_image', self.depth_msg, sensor.depth)):
            if role in wanted and pixels is not None:
                fill_time_msg(msg.header.stamp, stamp)
                msg.data = data_of(pixels)
                wanted[role].publish(msg)
        if 'points' in wanted and sensor.depth is not None:
            points = sensor.points()
            fill_time_msg(self.cloud_msg.header.stamp, stamp)
            self.cloud_msg.data = data_of(points)
            self.cloud_msg.is_dense = bool(np.isfinite(points).all())
            wanted['points'].publish(self.cloud_msg)
        if 'camera_info' in wanted:
            fill_time_msg(self.info_msg.header.stamp, stamp)
            wanted['camera_info'].publish(self.info_msg)

    def destroy(self):
        """Release the renderer along with the topics."""
        super().destroy()
        self.sensor.close()
