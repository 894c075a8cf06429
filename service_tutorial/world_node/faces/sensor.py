"""
The ROS faces of the sensor plugins: sensor_msgs LaserScan, Image with CameraInfo, and Imu.

A face makes its sensor active while one of its topics has a subscriber, and publishes each
reading the sensor hands it, stamped with the simulation time of the reading: nothing is
measured or built for a topic nobody listens to. It looks for subscribers a few times per wall
second (subscribers.py), when the world node has it look (at most every FACE_LOOK_PERIOD),
rather than through matched events: each event handler is one more entity every executor turn
waits on, and with four per robot a fleet of 50 ran a quarter slower.
Free-running (real_time_factor 0), a sensor is also held to its rate in wall time, as the
world node holds every stream: far faster than real time, a 5 Hz laser would otherwise cast
and publish hundreds of scans per wall second. Topics land where gazebo_ros puts them
(ros_names.plugin_topic); frames are the block's frameName (ROS 1) or frame_name (ROS 2), else
the sensor's link.
"""

import array
import math
import time

from rclpy.event_handler import PublisherEventCallbacks
from sensor_msgs.msg import CameraInfo, Image, Imu, LaserScan
from service_tutorial.conversions import fill_quaternion_msg, fill_time_msg
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.plugins.imu_sensor import ImuSensor
from service_tutorial.sim.plugins.imu_sensor import is_ros1_block as is_ros1_imu
from service_tutorial.sim.plugins.ray_sensor import RaySensor
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.ros_names import plugin_topic
from service_tutorial.world_node.subscribers import SubscriberWatch

# The one type a laser publishes here; gazebo_ros_ray_sensor can also give point clouds.
LASER_SCAN_TYPE = 'sensor_msgs/LaserScan'
# Tags that only the ROS 1 camera plugin reads.
_ROS1_CAMERA_TAGS = ('cameraName', 'imageTopicName', 'cameraInfoTopicName', 'frameName',
                     'robotNamespace', 'hackBaseline')


def _frame(block, ros1, sensor):
    """Return the frame a sensor's messages name: the block's, else the sensor's link."""
    frame = block.text('frameName' if ros1 else 'frame_name') or sensor.config.link
    return frame.lstrip('/')  # tf2 frames have no leading slash


def _diagonal(values):
    """Return a row-major 3x3 covariance with values on its diagonal, as float64[9]."""
    matrix = [0.0] * 9
    matrix[0], matrix[4], matrix[8] = (float(value) for value in values)
    return matrix


class SensorFace:
    """One sensor's topics: their subscribers switch the sensor on and off."""

    def __init__(self, node, sensor):
        """Start with no topics; subclasses make theirs with publisher()."""
        self.node = node
        self.sensor = sensor
        self.watch = SubscriberWatch()  # the sensor's publishers
        self.listened = False
        self.resume_at = math.inf  # wall time at which a sensor held free-running measures again
        self.next_look = 0.0  # wall time at which look() has something to do
        sensor.listener = self.reading_callback

    def publisher(self, msg_type, topic, depth):
        """Make a publisher of one of the sensor's topics."""
        # Without rclpy's two default event handlers, a publisher costs the executor nothing.
        publisher = self.node.create_publisher(
            msg_type, topic, depth,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self.watch.add(publisher)
        return publisher

    def look(self, wall_time):
        """Switch the sensor on or off as its topics have subscribers, or a hold ends."""
        listened = self.watch.listened()
        changed, self.listened = listened != self.listened, listened
        if wall_time >= self.resume_at:
            self.resume_at, changed = math.inf, True
        self.next_look = min(self.watch.next_look, self.resume_at)
        if changed:
            self._switch()

    def _switch(self):
        self.sensor.set_active(self.listened and self.resume_at == math.inf)

    def reading_callback(self, sensor):
        """Publish a reading; free-running, hold the sensor for its period of wall time."""
        self.publish_reading(sensor)
        node = self.node
        if node.has_parameter('real_time_factor') and \
                node.get_parameter('real_time_factor').value <= 0.0:
            self.resume_at = time.monotonic() + sensor.period
            self.next_look = min(self.watch.next_look, self.resume_at)
            self._switch()

    def publish_reading(self, sensor):
        """Publish the sensor's latest reading (each kind of face says how)."""
        raise NotImplementedError

    def destroy(self):
        """Stop the sensor and remove its topics from the node."""
        self.sensor.listener = None
        self.sensor.set_active(False)
        for publisher in self.watch.publishers:
            self.node.destroy_publisher(publisher)
        self.watch = SubscriberWatch()


class LaserScanFace(SensorFace):
    """A laser's sensor_msgs/LaserScan (gazebo_ros_laser, gazebo_ros_ray_sensor)."""

    def __init__(self, node, sensor, namespace):
        """Place the scan topic and fill in what every scan of this laser shares."""
        super().__init__(node, sensor)
        block, config = sensor.block, sensor.config
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
        msg = self.scan_msg = LaserScan()
        msg.header.frame_id = _frame(block, ros1, sensor)
        msg.angle_min, msg.angle_max = config.angle_min, config.angle_max
        msg.angle_increment = config.angle_increment
        msg.time_increment = 0.0  # every beam of a scan is cast at the same instant
        msg.scan_time = sensor.period
        msg.range_min, msg.range_max = config.range_min, config.range_max
        self.scan_pub = self.publisher(LaserScan, topic, 10)

    def publish_reading(self, sensor):
        """Publish the scan the laser just made."""
        msg = self.scan_msg
        fill_time_msg(msg.header.stamp, sensor.reading_time)
        msg.ranges = array.array('f', sensor.ranges.tobytes())
        self.scan_pub.publish(msg)


class CameraFace(SensorFace):
    """A camera's sensor_msgs/Image and CameraInfo (gazebo_ros_camera, ROS 1 and ROS 2)."""

    def __init__(self, node, sensor, namespace):
        """Place the image and camera_info topics and describe the camera once."""
        super().__init__(node, sensor)
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
        baseline = _number(block, 'hackBaseline' if ros1 else 'hack_baseline')
        frame = _frame(block, ros1, sensor)
        self.image_msg = Image()
        self.image_msg.header.frame_id = frame
        self.image_msg.height, self.image_msg.width = config.height, config.width
        self.image_msg.encoding = config.encoding
        self.image_msg.step = config.width * (1 if config.encoding == 'mono8' else 3)
        self.info_msg = camera_info(config, frame, baseline)
        self.image_pub = self.publisher(
            Image, plugin_topic(block, image_topic, robot_namespace=namespace), 2)
        self.info_pub = self.publisher(
            CameraInfo, plugin_topic(block, info_topic, robot_namespace=namespace), 2)

    def publish_reading(self, sensor):
        """Publish the frame the camera just rendered, and its camera_info."""
        stamp = sensor.reading_time
        if self.image_pub.get_subscription_count() > 0:
            msg = self.image_msg
            fill_time_msg(msg.header.stamp, stamp)
            msg.data = sensor.image.tobytes()
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
    msg.r = _diagonal((1.0, 1.0, 1.0))
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


class ImuFace(SensorFace):
    """An IMU's sensor_msgs/Imu (gazebo_ros_imu, ROS 1; gazebo_ros_imu_sensor, ROS 2)."""

    def __init__(self, node, sensor, namespace):
        """Place the topic and fill in the covariances, which follow from the noise."""
        super().__init__(node, sensor)
        block = sensor.block
        ros1 = is_ros1_imu(block)
        if ros1:
            topic = plugin_topic(block, '/default_imu', robot_namespace=namespace,
                                 ros1_tag='topicName')
        else:
            topic = plugin_topic(block, '~/out', robot_namespace=namespace)
        msg = self.imu_msg = Imu()
        msg.header.frame_id = _frame(block, ros1, sensor)
        msg.orientation_covariance = _diagonal(sensor.covariance('orientation'))
        msg.angular_velocity_covariance = _diagonal(sensor.covariance('angular_velocity'))
        msg.linear_acceleration_covariance = _diagonal(
            sensor.covariance('linear_acceleration'))
        self.imu_pub = self.publisher(Imu, topic, 10)

    def publish_reading(self, sensor):
        """Publish the IMU's latest reading."""
        msg = self.imu_msg
        fill_time_msg(msg.header.stamp, sensor.reading_time)
        fill_quaternion_msg(msg.orientation, sensor.orientation)
        for vector, values in ((msg.angular_velocity, sensor.angular_velocity),
                               (msg.linear_acceleration, sensor.linear_acceleration)):
            vector.x, vector.y, vector.z = (float(value) for value in values)
        self.imu_pub.publish(msg)


class SensorInterface:
    """The face of one sensor plugin of a kind; a class of PLUGIN_INTERFACES."""

    sensor_type = None  # the Sensor plugin class
    face_type = None  # the SensorFace class that publishes its readings
    streams = ()  # readings are published as the sensor makes them, not on the node's streams

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is a sensor of this kind."""
        return isinstance(plugin, cls.sensor_type)

    def __init__(self, node, world, model, plugin, namespace):
        """Give the sensor its topics, in the model's namespace."""
        # The node has each watcher look (SensorFace.look) once its next_look comes.
        self.watchers = [self.face_type(node, plugin, namespace)]

    def destroy(self):
        """Stop the sensors and remove their topics."""
        for face in self.watchers:
            face.destroy()
        self.watchers = []


class LaserScanInterface(SensorInterface):
    """The lasers of a model."""

    sensor_type = RaySensor
    face_type = LaserScanFace


class CameraInterface(SensorInterface):
    """The cameras of a model."""

    sensor_type = CameraSensor
    face_type = CameraFace


class ImuInterface(SensorInterface):
    """The IMUs of a model."""

    sensor_type = ImuSensor
    face_type = ImuFace


# Every sensor kind with a ROS face, for model_interface.PLUGIN_INTERFACES.
SENSOR_INTERFACES = (LaserScanInterface, CameraInterface, ImuInterface)
