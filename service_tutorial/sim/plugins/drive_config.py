"""
Parameters of the Gazebo drive plugins, in both generations' spellings, free of ROS.

gazebo_ros_diff_drive is written with ROS 1 names (leftJoint, wheelTorque...) or ROS 2 names
(left_joint, max_wheel_torque...), each generation with defaults of its own; ROS 1's
gazebo_ros_skid_steer_drive drives four wheels, two on each side. Each block becomes a
DiffDriveConfig: wheel pairs, limits, odometry, what the ROS face publishes, and notes on the
values gazebo_ros would have warned about and replaced by its default.
"""

from dataclasses import dataclass

from service_tutorial.sim.description import check_update_rate
from service_tutorial.sim.description import frame_id
from service_tutorial.sim.description import MAX_SIZE
from service_tutorial.sim.description import parse_numbers
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.validation import quoted

ODOMETRY_SOURCE_ENCODER = 0
ODOMETRY_SOURCE_WORLD = 1
# Odometry covariance diagonals of x, y, z, roll, pitch, yaw; gazebo_ros sets 1e12 (unknown)
# for the three a planar robot does not measure.
UNMEASURED = 1e12


def planar_covariance(x, y, yaw):
    """Return the six covariance diagonals of planar odometry with these x, y, yaw values."""
    return (x, y, UNMEASURED, UNMEASURED, UNMEASURED, yaw)


@dataclass(frozen=True)
class DiffDriveConfig:
    """
    Settings of a gazebo_ros drive plugin, in ROS 2 names and SI units.

    Wheel joints come in pairs, each pair with its own separation and diameter (every pair
    uses wheel_separation and wheel_diameter unless pair_separations and pair_diameters say
    otherwise). A ROS 1 legacyMode true is resolved while parsing by swapping the sides.
    """

    left_joints: tuple
    right_joints: tuple
    wheel_separation: float = 0.34  # metres, of the first pair
    wheel_diameter: float = 0.15  # metres, of the first pair
    pair_separations: tuple = ()
    pair_diameters: tuple = ()
    max_wheel_torque: float = 5.0  # N m on each wheel
    max_wheel_acceleration: float = 0.0  # m/s^2 at the wheel rim; 0 means unlimited
    odometry_frame: str = 'odom'
    robot_base_frame: str = 'base_footprint'
    odometry_source: int = ODOMETRY_SOURCE_WORLD
    publish_odom: bool = False  # the odometry topic
    publish_odom_tf: bool = False  # the odometry_frame -> robot_base_frame transform
    publish_wheel_tf: bool = False
    publish_wheel_joint_state: bool = False
    update_rate: float = 100.0  # Hz at which odometry is published
    # Diagonals of the odometry's pose covariance then twist covariance, or None.
    covariance: tuple = planar_covariance(1e-5, 1e-5, 1e-3) * 2
    legacy_mode: bool = False
    notes: tuple = ()  # values gazebo_ros would have warned about, and what was done

    @property
    def wheel_radius(self):
        """Return the radius of the first pair's wheels in metres."""
        return self.wheel_diameter / 2.0

    @property
    def left_joint(self):
        """Return the first left wheel joint, the one encoder odometry reads."""
        return self.left_joints[0]

    @property
    def right_joint(self):
        """Return the first right wheel joint, the one encoder odometry reads."""
        return self.right_joints[0]

    def wheel_pairs(self):
        """Return (left joint, right joint, separation, diameter) of every wheel pair."""
        count = len(self.left_joints)
        separations = self.pair_separations or (self.wheel_separation,) * count
        diameters = self.pair_diameters or (self.wheel_diameter,) * count
        return tuple(zip(self.left_joints, self.right_joints, separations, diameters))


# ROS 2 parameter name -> ROS 1 parameter name of gazebo_ros_diff_drive. ROS 1's publishTf
# false leaves out the odometry topic altogether, as ROS 2's publish_odom false does.
_ROS1_NAMES = {
    'left_joint': 'leftJoint',
    'right_joint': 'rightJoint',
    'wheel_separation': 'wheelSeparation',
    'wheel_diameter': 'wheelDiameter',
    'max_wheel_torque': 'wheelTorque',
    'max_wheel_acceleration': 'wheelAcceleration',
    'odometry_frame': 'odometryFrame',
    'robot_base_frame': 'robotBaseFrame',
    'odometry_source': 'odometrySource',
    'command_topic': 'commandTopic',
    'odometry_topic': 'odometryTopic',
    'publish_odom': 'publishTf',
    'publish_odom_tf': 'publishOdomTF',
    'publish_wheel_tf': 'publishWheelTF',
    'publish_wheel_joint_state': 'publishWheelJointState',
    'update_rate': 'updateRate',
}
_ROS1_ONLY = {'legacyMode', 'robotNamespace', 'rosDebugLevel', 'torque', 'wheelTorque'}
_ROS2_ONLY = {'num_wheel_pairs', 'covariance_x', 'covariance_y', 'covariance_yaw'}


def is_ros1_block(block):
    """Return True if a diff-drive block is written with gazebo_ros's ROS 1 parameter names."""
    tags = set(block.parameters)
    ros1 = tags & (set(_ROS1_NAMES.values()) | _ROS1_ONLY)
    ros2 = tags & (set(_ROS1_NAMES) | _ROS2_ONLY)
    return bool(ros1) and not ros2


def tag_name(block, key):
    """Return the tag a diff-drive parameter, named by its ROS 2 name, has in this block."""
    return _ROS1_NAMES.get(key, key) if is_ros1_block(block) else key


def parameter_texts(block, key):
    """Return the texts of a diff-drive parameter, by its ROS 2 name, in either generation."""
    return block.texts(tag_name(block, key))


def parameter(block, key, default=None):
    """Return the last text given for a diff-drive parameter such as command_topic, or default."""
    values = parameter_texts(block, key)
    return values[-1] if values else default


class _Reader:
    """Reads the values of one plugin block by their tags, collecting notes as it goes."""

    def __init__(self, block, title):
        self.block = block
        self.title = title
        self.notes = []

    def number(self, tag, default, *, positive=True, text=None):
        """Return a number tag's value: > 0 if positive, else >= 0."""
        if text is None:
            text = self.block.text(tag)
        if text is None:
            return default
        what = f'{self.title} <{tag}>'
        value = parse_numbers(text, what)
        if len(value) != 1 or value[0] < 0.0 or (positive and value[0] == 0.0):
            bound = '>' if positive else '>='
            raise UrdfError(f'{what} must be one number {bound} 0: {quoted(text)}')
        return value[0]

    def length(self, tag, default, *, text=None):
        """Return a length tag's value in metres: > 0 and at most MAX_SIZE."""
        value = self.number(tag, default, text=text)
        if value > MAX_SIZE:
            raise UrdfError(f'{self.title} <{tag}> must be at most {MAX_SIZE:g} m: {value:g}')
        return value

    def rate(self, tag, default):
        """Return a rate tag's value in Hz: >= 0 and at most MAX_UPDATE_RATE."""
        return check_update_rate(self.number(tag, default, positive=False),
                                 f'{self.title} <{tag}>')

    def frame(self, tag, default):
        """Return a frame tag's value as tf2 takes it (see description.frame_id)."""
        text = self.block.text(tag)
        return frame_id(text, f'{self.title} <{tag}>') if text else default

    def flag(self, tag, default, *, strict=False):
        """
        Return a true/false tag's value.

        strict: read as gazebo_ros's ROS 1 getParameterBoolean does, which takes only true
        and false and keeps the default, with a warning, for 1 and 0.
        """
        text = self.block.text(tag)
        if text is None:
            return default
        value = text.lower()
        if value not in ('true', 'false', '1', '0'):
            raise UrdfError(f'{self.title} <{tag}> must be true or false: {quoted(text)}')
        if strict and value in ('1', '0'):
            self.notes.append(f'{self.title} <{tag}> is {quoted(text)}, which gazebo_ros reads '
                              f'only as true or false; the default {str(default).lower()} is '
                              'kept')
            return default
        return value in ('true', '1')

    def text(self, tag, default):
        """Return a text tag's value."""
        return self.block.text(tag, default) or default

    def covariance(self, defaults):
        """Return planar covariance diagonals from <covariance_x|y|yaw>, pose then twist."""
        values = [self.number(f'covariance_{axis}', default, positive=False)
                  for axis, default in zip(('x', 'y', 'yaw'), defaults)]
        return planar_covariance(*values) * 2


def wheel_joints(block, robot, left_joints, right_joints, title):
    """Check wheel joint names against the robot; return them."""
    joints = {joint.name: joint for joint in robot.joints}
    for name in left_joints + right_joints:
        if name not in joints:
            raise UrdfError(f'{title} wheel joint {quoted(name)} is not a joint of the robot')
        if joints[name].type not in ('continuous', 'revolute'):
            raise UrdfError(f'{title} wheel joint {quoted(name)} is {joints[name].type}, '
                            'not continuous or revolute')
    if len(set(left_joints + right_joints)) != len(left_joints) + len(right_joints):
        raise UrdfError(f'{title} plugin names the same wheel joint twice')
    return tuple(left_joints), tuple(right_joints)


def read_diff_drive(block, robot):
    """Return the DiffDriveConfig of a gazebo_ros_diff_drive block of a yourdfpy robot."""
    if is_ros1_block(block):
        return _read_ros1_diff_drive(block, robot)
    return _read_ros2_diff_drive(block, robot)


def _odometry_source(reader, tag, own, other):
    """Return the odometry source: own spellings map to it, the other generation's to world."""
    text = reader.block.text(tag)
    if text is None:
        return ODOMETRY_SOURCE_WORLD
    value = text.lower()
    if value in own:
        return own[value]
    if value in other:
        reader.notes.append(f'{reader.title} <{tag}> {quoted(text)} is not read by this '
                            'generation of gazebo_ros, which keeps its default: world '
                            '(ground truth)')
        return ODOMETRY_SOURCE_WORLD
    spelled = ' or '.join(repr(name) for name in own)
    raise UrdfError(f'{reader.title} <{tag}> must be {spelled}: {quoted(text)}')


def _read_ros2_diff_drive(block, robot):
    """Read a diff-drive block of ROS 2's gazebo_ros (Foxy and later)."""
    reader = _Reader(block, 'diff-drive')
    pairs = 1
    if block.text('num_wheel_pairs') is not None:
        text = block.text('num_wheel_pairs')
        try:
            pairs = int(text)
        except ValueError:
            raise UrdfError(f'diff-drive <num_wheel_pairs> must be a whole number: '
                            f'{quoted(text)}') from None
        if pairs < 1:
            reader.notes.append(f'diff-drive <num_wheel_pairs> {quoted(text)} is less than 1; '
                                'gazebo_ros takes 1')
            pairs = 1
    left, right = block.texts('left_joint'), block.texts('right_joint')
    if len(left) != pairs or len(right) != pairs:
        raise UrdfError(f'diff-drive plugin names {len(left)} <left_joint> and {len(right)} '
                        f'<right_joint>, but <num_wheel_pairs> is {pairs}')
    left, right = wheel_joints(block, robot, left, right, 'diff-drive')
    per_pair = {}
    for tag, default in (('wheel_separation', 0.34), ('wheel_diameter', 0.15)):
        texts = block.texts(tag)
        if len(texts) > pairs:
            reader.notes.append(f'diff-drive gives {len(texts)} <{tag}> for {pairs} wheel '
                                'pairs; the extra ones are ignored, as gazebo_ros does')
        values = [reader.length(tag, default, text=text) for text in texts[:pairs]]
        per_pair[tag] = tuple(values + [default] * (pairs - len(values)))
    return DiffDriveConfig(
        left_joints=left, right_joints=right,
        wheel_separation=per_pair['wheel_separation'][0],
        wheel_diameter=per_pair['wheel_diameter'][0],
        pair_separations=per_pair['wheel_separation'],
        pair_diameters=per_pair['wheel_diameter'],
        max_wheel_torque=reader.number('max_wheel_torque', 5.0),
        max_wheel_acceleration=reader.number('max_wheel_acceleration', 0.0, positive=False),
        odometry_frame=reader.frame('odometry_frame', 'odom'),
        robot_base_frame=reader.frame('robot_base_frame', 'base_footprint'),
        odometry_source=_odometry_source(
            reader, 'odometry_source', {'0': ODOMETRY_SOURCE_ENCODER, '1': ODOMETRY_SOURCE_WORLD},
            ('encoder', 'world')),
        publish_odom=reader.flag('publish_odom', False),
        publish_odom_tf=reader.flag('publish_odom_tf', False),
        publish_wheel_tf=reader.flag('publish_wheel_tf', False),
        publish_wheel_joint_state=False,
        update_rate=reader.rate('update_rate', 100.0),
        covariance=reader.covariance((1e-5, 1e-5, 1e-3)),
        notes=tuple(reader.notes))


def _read_ros1_diff_drive(block, robot):
    """Read a diff-drive block of ROS 1's gazebo_ros (Melodic and Noetic)."""
    reader = _Reader(block, 'diff-drive')
    left, right = wheel_joints(block, robot, (reader.text('leftJoint', 'left_joint'),),
                               (reader.text('rightJoint', 'right_joint'),), 'diff-drive')
    legacy_mode = reader.flag('legacyMode', False)
    if legacy_mode:
        # Before Melodic, gazebo_ros drove each wheel with the other side's speed.
        left, right = right, left
    if block.text('torque') is not None and block.text('wheelTorque') is None:
        reader.notes.append('diff-drive <torque> is not read by gazebo_ros_diff_drive, whose '
                            'wheel torque limit is <wheelTorque>; its default 5 N m is used')
    return DiffDriveConfig(
        left_joints=left, right_joints=right,
        wheel_separation=reader.length('wheelSeparation', 0.34),
        wheel_diameter=reader.length('wheelDiameter', 0.15),
        max_wheel_torque=reader.number('wheelTorque', 5.0),
        max_wheel_acceleration=reader.number('wheelAcceleration', 0.0, positive=False),
        odometry_frame=reader.frame('odometryFrame', 'odom'),
        robot_base_frame=reader.frame('robotBaseFrame', 'base_footprint'),
        odometry_source=_odometry_source(
            reader, 'odometrySource',
            {'encoder': ODOMETRY_SOURCE_ENCODER, 'world': ODOMETRY_SOURCE_WORLD}, ('0', '1')),
        publish_odom=reader.flag('publishTf', True),
        publish_odom_tf=reader.flag('publishOdomTF', True, strict=True),
        publish_wheel_tf=reader.flag('publishWheelTF', False, strict=True),
        publish_wheel_joint_state=reader.flag('publishWheelJointState', False, strict=True),
        update_rate=reader.rate('updateRate', 100.0),
        # ROS 1's diff drive reports a fixed pose covariance and no twist covariance.
        covariance=planar_covariance(1e-5, 1e-5, 1e-3) + (0.0,) * 6,
        legacy_mode=legacy_mode,
        notes=tuple(reader.notes))


def read_skid_steer(block, robot):
    """Return the DiffDriveConfig of a ROS 1 gazebo_ros_skid_steer_drive block."""
    reader = _Reader(block, 'skid-steer')
    left, right = wheel_joints(
        block, robot,
        (reader.text('leftFrontJoint', 'left_front_joint'),
         reader.text('leftRearJoint', 'left_rear_joint')),
        (reader.text('rightFrontJoint', 'right_front_joint'),
         reader.text('rightRearJoint', 'right_rear_joint')), 'skid-steer')
    return DiffDriveConfig(
        left_joints=left, right_joints=right,
        wheel_separation=reader.length('wheelSeparation', 0.4),
        wheel_diameter=reader.length('wheelDiameter', 0.15),
        max_wheel_torque=reader.number('torque', 5.0),
        odometry_frame=reader.frame('odometryFrame', 'odom'),
        robot_base_frame=reader.frame('robotBaseFrame', 'base_footprint'),
        odometry_source=ODOMETRY_SOURCE_WORLD,
        publish_odom=True,
        publish_odom_tf=reader.flag('broadcastTF', False),
        update_rate=reader.rate('updateRate', 100.0),
        covariance=reader.covariance((1e-4, 1e-4, 1e-2)),
        notes=tuple(reader.notes))
