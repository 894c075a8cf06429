"""
What the faces of the sensor plugins share: subscribers switch a sensor on and off.

The laser (laser.py), camera (camera.py) and IMU (imu.py) faces are SensorFaces.

A face makes its sensor active while one of its topics has a subscriber, and publishes each
reading the sensor hands it, stamped with the simulation time of the reading: nothing is
measured or built for a topic nobody listens to. It looks for subscribers a few times per wall
second (subscribers.py), when the world node has it look (at most every FACE_LOOK_PERIOD),
rather than through matched events: each event handler is one more entity every executor turn
waits on, and with four per robot a fleet of 50 ran a quarter slower.
Free-running (real_time_factor 0, or a paused world's steps on request), a sensor is also held
to its rate in wall time, as the world node holds every stream: far faster than real time, a
5 Hz laser would otherwise cast and publish hundreds of scans per wall second. Topics land
where gazebo_ros puts them (ros_names.plugin_topic); frames are the block's frameName (ROS 1)
or frame_name (ROS 2), else the sensor's link. The topics are published by the world's sensor
node (sensor_node.py), in a DDS participant of its own: large frames in flight do not hold up
the world's answers.
"""

import math
import time

from service_tutorial.world_node.faces.face import PluginFace
from service_tutorial.world_node.subscribers import SubscriberWatch


def sensor_frame(block, ros1, sensor):
    """Return the frame a sensor's messages name: the block's, else the sensor's link."""
    frame = block.text('frameName' if ros1 else 'frame_name') or sensor.config.link
    return frame.lstrip('/')  # tf2 frames have no leading slash


def diagonal(values):
    """Return a row-major 3x3 covariance with values on its diagonal, as float64[9]."""
    matrix = [0.0] * 9
    matrix[0], matrix[4], matrix[8] = (float(value) for value in values)
    return matrix


class SensorFace(PluginFace):
    """One sensor's topics: their subscribers switch the sensor on and off."""

    sensor_type = None  # the Sensor plugin class the face serves

    def __init_subclass__(cls, *, sensor_type, **kwargs):
        """Make a face of the sensors of one kind: class LaserScanFace(..., sensor_type=...)."""
        super().__init_subclass__(**kwargs)
        cls.sensor_type = sensor_type

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is a sensor of this face's kind (gz's have faces of their own)."""
        return isinstance(plugin, cls.sensor_type) and not plugin.is_gz_system

    def __init__(self, node, world, model, plugin, namespace):
        """Start with no topics; each kind names its own and makes them with publisher()."""
        self.node = node
        self.sensor = sensor = plugin
        self.watch = SubscriberWatch()  # the sensor's publishers
        self.listened = False
        self.resume_at = math.inf  # wall time at which a sensor held free-running measures again
        self.next_look = 0.0  # wall time at which look() has something to do
        sensor.listener = self.reading_callback

    def publisher(self, msg_type, topic, depth):
        """Make a publisher of one of the sensor's topics (in make_topics()) on the sensor node."""
        publisher = self.node.sensor_node.create_publisher(msg_type, topic, depth)
        self.watch.add(publisher)
        return publisher

    @property
    def watchers(self):
        """Return the face itself: the node has it look for subscribers."""
        return (self,)

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
        pacer = getattr(self.node, 'pacer', None)  # free-running: factor 0, steps on request
        if pacer is not None and pacer.free_running:
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
            self.node.sensor_node.destroy_publisher(publisher)
        self.watch = SubscriberWatch()
