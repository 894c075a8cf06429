"""
ros_gz_bridge's mappings as its users write them, read without ROS: YAML files and arguments.

A YAML configuration is a sequence of maps, one per gz topic: `topic_name`, or
`ros_topic_name` and `gz_topic_name` (either alone names both sides), `ros_type_name` and
`gz_type_name` (both required), `direction` (BIDIRECTIONAL, the default, GZ_TO_ROS or
ROS_TO_GZ), `publisher_queue` and `subscriber_queue` (10) and `lazy` (false), as
ros_gz_bridge's bridge_config reads them. parameter_bridge's arguments say the same in one
word: `topic@ros_type@gz_type`, where the second delimiter is '@' for both ways, '[' for gz to
ROS and ']' for ROS to gz, and an optional `@gz_topic` at the end names the gz side apart.

What ros_gz_bridge would refuse is refused here with the file and entry named: a file that is
not YAML, is not a sequence, or is larger than MAX_CONFIG_BYTES (checked before it is read);
an entry that is not a map, lacks a type, pairs types ros_gz_bridge has no conversion for, or
names a topic that is not a valid ROS or gz name. A bad entry is left out and the others
apply, as ros_gz_bridge does. Whether the world can serve a valid pair is gz_bridge.py's to say.
"""

from dataclasses import dataclass
import os
import re

from service_tutorial.sim.plugins.gz_names import valid_topic
import yaml

GZ_TO_ROS = 'GZ_TO_ROS'
ROS_TO_GZ = 'ROS_TO_GZ'
BIDIRECTIONAL = 'BIDIRECTIONAL'
DIRECTIONS = (BIDIRECTIONAL, GZ_TO_ROS, ROS_TO_GZ)
# parameter_bridge's delimiter after the ROS type, and the direction it means.
ARGUMENT_DIRECTIONS = {'@': BIDIRECTIONAL, '[': GZ_TO_ROS, ']': ROS_TO_GZ}
DEFAULT_QUEUE = 10
# A bridge configuration names a few dozen topics: a megabyte is far beyond any.
MAX_CONFIG_BYTES = 1 << 20
MAX_QUEUE = 1 << 16
KEYS = ('topic_name', 'ros_topic_name', 'gz_topic_name', 'ros_type_name', 'gz_type_name',
        'direction', 'publisher_queue', 'subscriber_queue', 'lazy')
# gz message type (after gz.msgs.) -> the ROS types ros_gz_bridge (Jazzy) converts it to/from.
ROS_GZ_PAIRS = {
    'Actuators': ('actuator_msgs/msg/Actuators',),
    'AnnotatedAxisAligned2DBox': ('vision_msgs/msg/Detection2D',),
    'AnnotatedAxisAligned2DBox_V': ('vision_msgs/msg/Detection2DArray',),
    'AnnotatedOriented3DBox': ('vision_msgs/msg/Detection3D',),
    'AnnotatedOriented3DBox_V': ('vision_msgs/msg/Detection3DArray',),
    'Altimeter': ('ros_gz_interfaces/msg/Altimeter',),
    'Any': ('rcl_interfaces/msg/ParameterValue',),
    'BatteryState': ('sensor_msgs/msg/BatteryState',),
    'Boolean': ('std_msgs/msg/Bool',),
    'CameraInfo': ('sensor_msgs/msg/CameraInfo',),
    'Clock': ('rosgraph_msgs/msg/Clock',),
    'Color': ('std_msgs/msg/ColorRGBA',),
    'Contact': ('ros_gz_interfaces/msg/Contact',),
    'Contacts': ('ros_gz_interfaces/msg/Contacts',),
    'Dataframe': ('ros_gz_interfaces/msg/Dataframe',),
    'Double': ('std_msgs/msg/Float64',),
    'Empty': ('std_msgs/msg/Empty',),
    'Entity': ('ros_gz_interfaces/msg/Entity',),
    'EntityWrench': ('ros_gz_interfaces/msg/EntityWrench',),
    'Float': ('std_msgs/msg/Float32',),
    'Float_V': ('ros_gz_interfaces/msg/Float32Array',),
    'FluidPressure': ('sensor_msgs/msg/FluidPressure',),
    'GUICamera': ('ros_gz_interfaces/msg/GuiCamera',),
    'Header': ('std_msgs/msg/Header',),
    'IMU': ('sensor_msgs/msg/Imu',),
    'Image': ('sensor_msgs/msg/Image',),
    'Int32': ('std_msgs/msg/Int32',),
    'JointTrajectory': ('trajectory_msgs/msg/JointTrajectory',),
    'JointWrench': ('ros_gz_interfaces/msg/JointWrench',),
    'Joy': ('sensor_msgs/msg/Joy',),
    'LaserScan': ('sensor_msgs/msg/LaserScan',),
    'Light': ('ros_gz_interfaces/msg/Light',),
    'Magnetometer': ('sensor_msgs/msg/MagneticField',),
    'MaterialColor': ('ros_gz_interfaces/msg/MaterialColor',),
    'Model': ('sensor_msgs/msg/JointState',),
    'NavSat': ('sensor_msgs/msg/NavSatFix', 'gps_msgs/msg/GPSFix'),
    'Odometry': ('nav_msgs/msg/Odometry',),
    'OdometryWithCovariance': ('nav_msgs/msg/Odometry',),
    'Param': ('ros_gz_interfaces/msg/ParamVec',),
    'Param_V': ('ros_gz_interfaces/msg/ParamVec',),
    'PointCloudPacked': ('sensor_msgs/msg/PointCloud2',),
    'Pose': ('geometry_msgs/msg/Pose', 'geometry_msgs/msg/PoseStamped',
             'geometry_msgs/msg/Transform', 'geometry_msgs/msg/TransformStamped'),
    'PoseWithCovariance': ('geometry_msgs/msg/PoseWithCovariance',
                           'geometry_msgs/msg/PoseWithCovarianceStamped'),
    'Pose_V': ('geometry_msgs/msg/PoseArray', 'tf2_msgs/msg/TFMessage'),
    'Quaternion': ('geometry_msgs/msg/Quaternion',),
    'SensorNoise': ('ros_gz_interfaces/msg/SensorNoise',),
    'StringMsg': ('std_msgs/msg/String',),
    'StringMsg_V': ('ros_gz_interfaces/msg/StringVec',),
    'Time': ('builtin_interfaces/msg/Time',),
    'TrackVisual': ('ros_gz_interfaces/msg/TrackVisual',),
    'Twist': ('geometry_msgs/msg/Twist', 'geometry_msgs/msg/TwistStamped'),
    'TwistWithCovariance': ('geometry_msgs/msg/TwistWithCovariance',
                            'geometry_msgs/msg/TwistWithCovarianceStamped'),
    'UInt32': ('std_msgs/msg/UInt32',),
    'Vector3d': ('geometry_msgs/msg/Point', 'geometry_msgs/msg/Vector3'),
    'VideoRecord': ('ros_gz_interfaces/msg/VideoRecord',),
    'Wrench': ('geometry_msgs/msg/Wrench', 'geometry_msgs/msg/WrenchStamped'),
}
KNOWN_ROS_TYPES = frozenset(ros for pairs in ROS_GZ_PAIRS.values() for ros in pairs)
GZ_PREFIXES = ('gz.msgs.', 'ignition.msgs.')  # the second, Fortress's, is still read
# A ROS name: '/', '~' or a token first, then tokens of letters, digits and '_' between '/'.
_TOKEN = '[A-Za-z_][A-Za-z0-9_]*'
_ROS_TOPIC = re.compile(f'(?:~/|/)?{_TOKEN}(?:/{_TOKEN})*')
_ROS_TYPE = re.compile(f'({_TOKEN})/(?:msg/)?({_TOKEN})')
MAX_NAME_LENGTH = 255


class BridgeConfigError(ValueError):
    """A bridge configuration or argument ros_gz_bridge would refuse; the message says why."""


@dataclass(frozen=True)
class BridgeEntry:
    """One mapping of ros_gz_bridge: a gz topic and the ROS topic it crosses to or from."""

    ros_name: str  # as written: relative to the bridge's namespace unless absolute
    gz_name: str  # made valid and absolute, as gz-transport takes it
    ros_type: str  # pkg/msg/Name
    gz_type: str  # gz.msgs.Name
    direction: str = BIDIRECTIONAL
    publisher_queue: int = DEFAULT_QUEUE
    subscriber_queue: int = DEFAULT_QUEUE
    lazy: bool = False

    def as_yaml_entry(self):
        """Return the entry as a map of ros_gz_bridge's YAML keys."""
        return {'ros_topic_name': self.ros_name, 'gz_topic_name': self.gz_name,
                'ros_type_name': self.ros_type, 'gz_type_name': self.gz_type,
                'direction': self.direction, 'publisher_queue': self.publisher_queue,
                'subscriber_queue': self.subscriber_queue, 'lazy': self.lazy}


@dataclass(frozen=True)
class ConfigReading:
    """What a configuration gave: its valid entries, and one error per entry left out."""

    entries: tuple
    errors: tuple


def read_config_file(path, *, expand_gz=None):
    """Read a bridge YAML file (expand_gz: as read_config_text's); BridgeConfigError if refused."""
    try:
        size = os.stat(path).st_size
        if size > MAX_CONFIG_BYTES:
            raise BridgeConfigError(f'bridge configuration {path}: {size} bytes is more than '
                                    f'the limit of {MAX_CONFIG_BYTES}')
        with open(path, 'rb') as config:
            data = config.read(MAX_CONFIG_BYTES + 1)
    except OSError as error:
        raise BridgeConfigError(f'bridge configuration {path}: cannot be read '
                                f'({error.strerror or error})') from None
    if len(data) > MAX_CONFIG_BYTES:  # it grew while being read
        raise BridgeConfigError(f'bridge configuration {path}: more than the limit of '
                                f'{MAX_CONFIG_BYTES} bytes')
    try:
        text = data.decode('utf-8')
    except UnicodeDecodeError as error:
        raise BridgeConfigError(f'bridge configuration {path}: not UTF-8 text ({error})') \
            from None
    return read_config_text(text, source=path, expand_gz=expand_gz)


def read_config_text(text, *, source, expand_gz=None):
    """
    Read a bridge configuration's YAML text; source names it in errors (the file's path).

    expand_gz: a function that expands a gz topic name written in the file (parameter_bridge's
    expand_gz_topic_names), or None to take them as written.
    """
    if len(text) > MAX_CONFIG_BYTES:
        raise BridgeConfigError(f'bridge configuration {source}: more than the limit of '
                                f'{MAX_CONFIG_BYTES} bytes')
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as error:
        where = getattr(error, 'problem_mark', None)
        at = f' at line {where.line + 1}' if where is not None else ''
        problem = getattr(error, 'problem', None) or error
        raise BridgeConfigError(f'bridge configuration {source}: not YAML{at} ({problem})') \
            from None
    if document is None:
        raise BridgeConfigError(f'bridge configuration {source}: the file is empty')
    return read_config_document(document, source=source, expand_gz=expand_gz)


def read_config_document(document, *, source, expand_gz=None):
    """Read a bridge configuration parsed from YAML; the arguments are read_config_text's."""
    if not isinstance(document, list):
        raise BridgeConfigError(f'bridge configuration {source}: the top level must be a YAML '
                                f'sequence of maps, one per topic, not a {_kind(document)}')
    entries, errors = [], []
    for index, item in enumerate(document, 1):
        try:
            entries.append(parse_entry(item, expand_gz=expand_gz))
        except BridgeConfigError as error:
            errors.append(f'bridge configuration {source}, entry {index}'
                          f'{_entry_name(item)}: {error}')
    return ConfigReading(tuple(entries), tuple(errors))


def parse_entry(item, *, expand_gz=None):
    """Return the BridgeEntry of one map of a YAML configuration, or raise BridgeConfigError."""
    if not isinstance(item, dict):
        raise BridgeConfigError(f'an entry must be a YAML map, not a {_kind(item)}')
    values = {key: _text(item, key) for key in KEYS[:6]}
    topic, ros_topic, gz_topic = (values[key] for key in KEYS[:3])
    for other in ('ros_topic_name', 'gz_topic_name'):
        if topic and values[other]:
            raise BridgeConfigError(f'topic_name and {other} are mutually exclusive')
    if not values['ros_type_name'] or not values['gz_type_name']:
        raise BridgeConfigError('both ros_type_name and gz_type_name must be set')
    direction = values['direction'] or BIDIRECTIONAL
    if direction not in DIRECTIONS:
        raise BridgeConfigError(f'invalid direction {direction!r}: one of '
                                f'{", ".join(DIRECTIONS)}')
    ros_name = topic or ros_topic or gz_topic
    gz_name = topic or gz_topic or ros_topic
    if not ros_name:
        raise BridgeConfigError('no topic: set topic_name, or ros_topic_name and/or '
                                'gz_topic_name')
    if expand_gz is not None:
        gz_name = expand_gz(gz_name)
    return make_entry(ros_name, gz_name, values['ros_type_name'], values['gz_type_name'],
                      direction, publisher_queue=_queue(item, 'publisher_queue'),
                      subscriber_queue=_queue(item, 'subscriber_queue'),
                      lazy=_flag(item, 'lazy'))


def parse_argument(argument):
    """Return the BridgeEntry of a parameter_bridge argument (topic@ros_type@gz_type...)."""
    topic, at, rest = argument.partition('@')
    if not topic or not at or not rest:
        raise BridgeConfigError(f'argument {argument!r} is not topic@ros_type@gz_type '
                                '(or [ or ] in place of the second @)')
    # The first of ']', '[' or '@' after the ROS type says the direction, as parameter_bridge
    # looks for them in that order.
    for delimiter in (']', '[', '@'):
        position = rest.find(delimiter)
        if position > 0:
            break
    else:
        if '/srv/' in rest:
            raise BridgeConfigError(f'argument {argument!r} bridges a service, which this world '
                                    'does not serve through a bridge')
        raise BridgeConfigError(f'argument {argument!r} has no gz type after the ROS type')
    ros_type, gz_part = rest[:position], rest[position + 1:]
    if '/srv/' in ros_type:
        raise BridgeConfigError(f'argument {argument!r} bridges a service, which this world '
                                'does not serve through a bridge')
    gz_type, _, gz_topic = gz_part.partition('@')
    if not gz_type:
        raise BridgeConfigError(f'argument {argument!r} has no gz type after the ROS type')
    return make_entry(topic, gz_topic or topic, ros_type, gz_type, ARGUMENT_DIRECTIONS[
        rest[position]])


def make_entry(ros_name, gz_name, ros_type, gz_type, direction=BIDIRECTIONAL, **settings):
    """Return a BridgeEntry whose names and types are checked and written as ros_gz's are."""
    ros_type, gz_type = ros_type_name(ros_type), gz_type_name(gz_type)
    pairs = ROS_GZ_PAIRS.get(gz_type[len('gz.msgs.'):])
    if pairs is None:
        raise BridgeConfigError(f'unknown gz type {gz_type!r}: ros_gz_bridge converts none '
                                'of that name')
    if ros_type not in pairs:
        if ros_type not in KNOWN_ROS_TYPES:
            raise BridgeConfigError(f'unknown ROS type {ros_type!r}: ros_gz_bridge converts '
                                    'none of that name')
        raise BridgeConfigError(f'{ros_type} and {gz_type} do not go together: '
                                f'{gz_type} bridges to {" or ".join(pairs)}')
    if len(ros_name) > MAX_NAME_LENGTH or not _ROS_TOPIC.fullmatch(ros_name):
        raise BridgeConfigError(f'ROS topic {ros_name!r} is not a valid ROS name: tokens of '
                                'ASCII letters, digits and underscores between slashes, '
                                'none starting with a digit')
    valid_gz = valid_topic(gz_name) if len(gz_name) <= MAX_NAME_LENGTH else None
    if valid_gz is None:
        raise BridgeConfigError(f'gz topic {gz_name!r} is not a valid gz topic name')
    return BridgeEntry(ros_name, valid_gz, ros_type, gz_type, direction, **settings)


def ros_type_name(name):
    """Return a ROS message type as pkg/msg/Name (pkg/Name is read too)."""
    match = _ROS_TYPE.fullmatch(name.strip())
    if match is None:
        raise BridgeConfigError(f'ROS type {name!r} is not a message type name '
                                '(package/msg/Type)')
    return f'{match.group(1)}/msg/{match.group(2)}'


def gz_type_name(name):
    """Return a gz message type as gz.msgs.Name (ignition.msgs.Name is read too)."""
    name = name.strip()
    for prefix in GZ_PREFIXES:
        if name.startswith(prefix) and len(name) > len(prefix):
            return 'gz.msgs.' + name[len(prefix):]
    raise BridgeConfigError(f'gz type {name!r} is not a gz message type (gz.msgs.Type)')


def _text(item, key):
    """Return a key's value as text ('' if absent); refuse a map or a list."""
    value = item.get(key)
    if value is None:
        return ''
    if isinstance(value, (dict, list)):
        raise BridgeConfigError(f'{key} must be a single value, not a {_kind(value)}')
    return str(value).strip()


def _queue(item, key):
    value = item.get(key, DEFAULT_QUEUE)
    if isinstance(value, bool) or not isinstance(value, int) or not 0 < value <= MAX_QUEUE:
        raise BridgeConfigError(f'{key} must be a whole number from 1 to {MAX_QUEUE}: '
                                f'{value!r}')
    return value


def _flag(item, key):
    value = item.get(key, False)
    if not isinstance(value, bool):
        raise BridgeConfigError(f'{key} must be true or false: {value!r}')
    return value


def _kind(value):
    """Name the YAML kind of a value, for an error."""
    if isinstance(value, dict):
        return 'map'
    if isinstance(value, list):
        return 'sequence'
    return f'{type(value).__name__} ({str(value)[:40]!r})'


def _entry_name(item):
    """Return ' (topic)' naming an entry by its topic, or '' if it names none."""
    if isinstance(item, dict):
        for key in KEYS[:3]:
            if isinstance(item.get(key), str):
                return f' ({item[key][:80]})'
    return ''
