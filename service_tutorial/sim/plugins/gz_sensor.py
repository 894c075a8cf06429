"""
What gz-sim's sensors share, free of ROS: their gz topic, their frame, always_on.

A gz-sim sensor is a <sensor> with no <plugin>, simulated by its world's systems (Sensors, Imu,
NavSat); each kind here stands in for one and reuses the Gazebo Classic sensor that measures
the same (a lidar casts the Classic laser's rays, a camera draws with its renderer). Its topic
is its <topic> made valid as gz-transport makes it, else gz's default below the sensor,
/world/<world>/model/<model>/link/<link>/sensor/<sensor>/<suffix>; a <topic> gz cannot take
gives way to the default, as gz-sim does, and is named in a note. Its frame is <gz_frame_id>,
else its scoped name <model>/<link>/<sensor> as ros_gz_bridge writes it. <always_on> is read
and checked, and changes nothing, as in gz-sim 8: a sensor measures at its <update_rate>
whenever one of its topics is listened to.
"""

from service_tutorial.sim.description import frame_id
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import gz_names
from service_tutorial.sim.validation import quoted

_TRUE, _FALSE = ('true', '1'), ('false', '0')


def gz_sensor_fields(sensor, robot):
    """Return the fields every gz sensor's config has, read from its SensorBlock."""
    notes = []
    text = sensor.text('topic')
    topic = gz_names.valid_topic(text) if text else None
    if text and topic is None:
        notes.append(f'sensor {quoted(sensor.name)} <topic> {quoted(text)} is no valid gz '
                     "topic; the sensor's default is used, as gz-sim does")
    frame = sensor.text('gz_frame_id')
    always_on = (sensor.text('always_on') or 'true').lower()
    if always_on not in _TRUE + _FALSE:
        raise UrdfError(f'sensor {quoted(sensor.name)} <always_on> must be true or false: '
                        f'{quoted(always_on)}')
    return {'robot_name': robot.name, 'topic': topic, 'always_on': always_on in _TRUE,
            'notes': tuple(notes),
            'gz_frame_id': frame_id(frame, f'sensor {quoted(sensor.name)} <gz_frame_id>')
            if frame else None}


def parent_topic(topic):
    """Return the topic a topic lies below: /a/b/image -> /a/b."""
    return topic.rpartition('/')[0]


class GzSensor:
    """The part of a gz sensor plugin that names its topics and frame (mixed in first)."""

    is_gz_system = True

    def gz_topic(self, model_name, world_name, suffix=''):
        """Return the sensor's <topic>, else gz's default below it with a suffix (scan...)."""
        config = self.config
        return config.topic or gz_names.sensor_topic(world_name, model_name, config.link,
                                                     config.name, suffix)

    def gz_frame(self, model_name):
        """Return the frame of the sensor's messages: <gz_frame_id>, else its scoped name."""
        config = self.config
        return config.gz_frame_id or gz_names.sensor_frame(model_name, config.link, config.name)
