"""
A camera's face (gazebo_ros_camera, ROS 1 and ROS 2): sensor_msgs/Image and CameraInfo.

ROS 1's block advertises both under robotNamespace/cameraName; ROS 2's under camera_name.
CameraInfo describes a pinhole without distortion, with Gazebo's hackBaseline for a stereo
pair's right camera.
"""

from sensor_msgs.msg import CameraInfo, Image
from service_tutorial.conversions import fill_time_msg, pixel_bytes
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.faces.sensor import diagonal, sensor_frame, SensorFace
from service_tutorial.world_node.ros_names import plugin_topic

# Tags that only the ROS 1 camera plugin reads.
_ROS1_CAMERA_TAGS = ('cameraName', 'imageTopicName', 'cameraInfoTopicName', 'frameName',
                     'robotNamespace', 'hackBaseline')


class CameraFace(SensorFace, sensor_type=CameraSensor):
    """A camera's sensor_msgs/Image and CameraInfo (gazebo_ros_camera, ROS 1 and ROS 2)."""

    def __init__(self, node, world, model, plugin, namespace):
        """Name the image and camera_info topics and the frame of the images."""
        super().__init__(node, world, model, plugin, namespace)
        sensor = plugin
        block, config = sensor.block, sensor.config
        ros1 = any(tag in block.parameters for tag in _ROS1_CAMERA_TAGS)
        if ros1:
            # ROS 1 advertises both under robotNamespace/cameraName.
            camera_name = block.text('cameraName', '')
            image_topic, info_topic = (
                name if name.startswith('/') or not camera_name else f'{camera_name}/{name}'
                for name in (block.text('imageTopicName', 'image_raw'),
                             block.text('cameraInfoTopicName', 'camera_info')))
        else:
            camera_name = block.text('camera_name', config.name)
            image_topic, info_topic = f'{camera_name}/image_raw', f'{camera_name}/camera_info'
        self.baseline = _number(block, 'hackBaseline' if ros1 else 'hack_baseline')
        self.frame = sensor_frame(block, ros1, sensor)
        self.topics = tuple(plugin_topic(block, topic, robot_namespace=namespace)
                            for topic in (image_topic, info_topic))
        self.image_pub = self.info_pub = self.image_msg = self.info_msg = None

    def make_topics(self):
        """Make the image and camera_info topics and describe the camera once."""
        config = self.sensor.config
        self.image_msg = Image()
        self.image_msg.header.frame_id = self.frame
        self.image_msg.height, self.image_msg.width = config.height, config.width
        self.image_msg.encoding = config.encoding
        self.image_msg.step = config.width * (1 if config.encoding == 'mono8' else 3)
        self.info_msg = camera_info(config, self.frame, self.baseline)
        image_topic, info_topic = self.topics
        self.image_pub = self.publisher(Image, image_topic, 2)
        self.info_pub = self.publisher(CameraInfo, info_topic, 2)

    def publish_reading(self, sensor):
        """Publish the frame the camera just rendered, and its camera_info."""
        stamp = sensor.reading_time
        if self.image_pub.get_subscription_count() > 0:
            msg = self.image_msg
            fill_time_msg(msg.header.stamp, stamp)
            msg.data = pixel_bytes(sensor.image)
            self.image_pub.publish(msg)
        if self.info_pub.get_subscription_count() > 0:
            fill_time_msg(self.info_msg.header.stamp, stamp)
            self.info_pub.publish(self.info_msg)

    def destroy(self):
        """Release the renderer along with the topics."""
        super().destroy()
        self.sensor.close()


def camera_info(config, frame, baseline=0.0):
    """Return the CameraInfo of a camera: no distortion, K from its field of view and size."""
    msg = CameraInfo()
    msg.header.frame_id = frame
    msg.height, msg.width = config.height, config.width
    msg.distortion_model = 'plumb_bob'
    msg.d = [0.0] * 5
    k = config.intrinsic_matrix()
    msg.k = [float(value) for value in k.ravel()]
    msg.r = diagonal((1.0, 1.0, 1.0))
    # A stereo pair's right camera carries -fx * baseline in P (Gazebo's hackBaseline).
    msg.p = [float(k[0, 0]), 0.0, float(k[0, 2]), -float(k[0, 0]) * baseline,
             0.0, float(k[1, 1]), float(k[1, 2]), 0.0,
             0.0, 0.0, 1.0, 0.0]
    return msg


def _number(block, tag):
    text = block.text(tag, '0')
    try:
        return float(text)
    except ValueError:
        raise WorldError(f'plugin {quoted(block.name)} <{tag}> is not a number: '
                         f'{quoted(text)}') from None
