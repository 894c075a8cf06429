"""
gz-sim's names for the topics and frames of its systems and sensors, free of ROS.

A system's or sensor's topic is the <topic> it is given, or gz's default below its model or its
sensor: /model/<model>/cmd_vel, /world/<world>/model/<model>/link/<link>/sensor/<sensor>/scan.
gz-transport makes a name valid as TopicUtils::AsValidTopic does: a space becomes '_', '@', '~',
'//' and ':=' are dropped, and what is left must not be empty or '/'; a relative name lies
below '/'. A system takes the first of its candidates that is valid (gz-sim's validTopic), so
a <topic> that cannot be one gives way to the default. Names of nested models are scoped with
'::' (mast::pole), which a topic writes /model/<outer>/model/<inner>/link/<link>.

A sensor's frame is its <gz_frame_id>, else its scoped name <model>::<link>::<sensor>, which
ros_gz_bridge writes with '/' for '::' (tb3/imu_link/tb3_imu).
"""

SCOPE = '::'
# gz-sim's name for a world that names none, which gz topics of sensors then name.
DEFAULT_WORLD_NAME = 'default'
# The longest name gz-transport takes (kMaxNameLength).
MAX_TOPIC_LENGTH = 65535
_DROPPED = ('@', '~', '//', ':=')


def valid_topic(text):
    """Return a topic name as gz-transport makes it valid (absolute), or None if it cannot be."""
    if text is None:
        return None
    topic = text.replace(' ', '_')
    for dropped in _DROPPED:
        topic = topic.replace(dropped, '')
    if not topic or topic == '/' or len(topic) > MAX_TOPIC_LENGTH or '//' in topic:
        return None
    topic = topic if topic.startswith('/') else '/' + topic
    return topic.rstrip('/') or None


def first_valid_topic(*candidates):
    """Return the first candidate that is a valid topic, made valid; None if none is."""
    for candidate in candidates:
        topic = valid_topic(candidate)
        if topic is not None:
            return topic
    return None


def model_path(model_name):
    """Return a (scoped) model's part of a topic: 'model/a' or 'model/a/model/b'."""
    return '/'.join(f'model/{part}' for part in model_name.split(SCOPE))


def model_topic(model_name, *parts):
    """Return gz's default topic below a model: /model/<model>/<parts...>."""
    return '/' + '/'.join((model_path(model_name),) + parts)


def world_model_topic(world_name, model_name, *parts):
    """Return gz's default topic below a model of a world: /world/<w>/model/<m>/<parts...>."""
    return f'/world/{world_name}/' + '/'.join((model_path(model_name),) + parts)


def sensor_topic(world_name, model_name, link_name, sensor_name, suffix=''):
    """Return a sensor's default topic: /world/<w>/model/<m>/link/<l>/sensor/<s>[/suffix]."""
    *nested, link = link_name.split(SCOPE)
    scoped_model = SCOPE.join([model_name] + nested)
    parts = ('link', link, 'sensor', sensor_name) + ((suffix,) if suffix else ())
    return world_model_topic(world_name, scoped_model, *parts)


def ros_frame(gz_frame):
    """Return a gz frame id as ros_gz_bridge hands it to ROS: '::' becomes '/'."""
    return gz_frame.replace(SCOPE, '/')


def sensor_frame(model_name, link_name, sensor_name):
    """Return a sensor's default frame, its scoped name as ros_gz_bridge writes it."""
    return ros_frame(SCOPE.join((model_name, link_name, sensor_name)))


def model_frame(model_name, frame):
    """Return a frame gz names below a model: <model>/<frame> (<model>/odom)."""
    return ros_frame(f'{model_name}/{frame}')
