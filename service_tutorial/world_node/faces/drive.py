"""
The face of a drive (gazebo_ros_diff_drive, gazebo_ros_skid_steer_drive): cmd_vel, odom, joints.

Topics land where ros_names.plugin_topic() says gazebo_ros would put them. The velocity
commands never wake the node's executor: the node has the face take them at each tick
(taken_at_tick.py), and the drive applies them in the steps that follow.
"""

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
from sensor_msgs.msg import JointState
from service_tutorial.conversions import fill_joint_state_msg, fill_pose_msg
from service_tutorial.conversions import fill_time_msg, fill_twist_msg
from service_tutorial.sim.plugins.diff_drive import DiffDrive, MAX_WHEEL_RIM_SPEED
from service_tutorial.sim.plugins.drive_config import is_ros1_block
from service_tutorial.sim.plugins.drive_config import ODOMETRY_SOURCE_ENCODER
from service_tutorial.sim.validation import finite_number
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.faces.face import PluginFace
from service_tutorial.world_node.pacing import JOINT_STATES_STREAM, ODOMETRY_STREAM
from service_tutorial.world_node.ros_names import plugin_topic
from service_tutorial.world_node.subscribers import SubscriberWatch
from service_tutorial.world_node.taken_at_tick import take_messages, TakenAtTick


def publishes_joint_states(drive):
    """
    Tell whether a drive's face publishes joint_states.

    A ROS 1 block says so (publishWheelJointState). ROS 2's diff drive has no such switch,
    Gazebo leaving joint states to another plugin; here it publishes them, as the world always
    has, for robot_state_publisher.
    """
    ros2_diff_drive = type(drive) is DiffDrive and not is_ros1_block(drive.block)
    return drive.config.publish_wheel_joint_state or ros2_diff_drive


class DriveFace(PluginFace):
    """A drive's topics (diff drive or skid steer): cmd_vel in, odom and joint_states out."""

    streams = (ODOMETRY_STREAM, JOINT_STATES_STREAM)
    takes_commands = True

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is a gazebo_ros drive (a diff drive or skid steer)."""
        return isinstance(plugin, DiffDrive)

    def __init__(self, node, world, model, plugin, namespace):
        """Name the drive's topics; namespace is the model's, normalised ('' or '/a/b')."""
        self.node = node
        self.world = world
        self.model = model
        self.drive = plugin
        config, block = plugin.config, plugin.block
        self.cmd_vel_topic, odom_topic, joint_states_topic = (
            plugin_topic(block, topic, robot_namespace=namespace, ros1_tag=ros1_tag)
            for topic, ros1_tag in (('cmd_vel', 'commandTopic'), ('odom', 'odometryTopic'),
                                    ('joint_states', None)))
        # None: the block asks for no such topic (its name was still checked).
        self.odom_topic = odom_topic if config.publish_odom else None
        self.joint_states_topic = joint_states_topic if publishes_joint_states(plugin) else None
        self.encoder_odometry = config.odometry_source == ODOMETRY_SOURCE_ENCODER
        self.cmd_vel_sub = self.odom_pub = self.joint_states_pub = None
        self._publishers = {}  # stream -> (publish(now), SubscriberWatch of its topic)
        self.odom_msg = self.joint_states_msg = None

    @property
    def topics(self):
        """Return the names of the topics the drive makes: cmd_vel, odom, joint_states."""
        return tuple(topic for topic in (self.cmd_vel_topic, self.odom_topic,
                                         self.joint_states_topic) if topic is not None)

    def make_topics(self):
        """Make the drive's topics: cmd_vel, and odom and joint_states as the block asks."""
        node, config = self.node, self.drive.config
        # Filled in and published again every time: publish() copies the message.
        self.odom_msg = Odometry()
        if config.covariance is not None:
            # Six pose then six twist variances, on the diagonals of the 6 x 6 matrices.
            for index, variance in enumerate(config.covariance):
                matrix = self.odom_msg.pose if index < 6 else self.odom_msg.twist
                matrix.covariance[7 * (index % 6)] = float(variance)
        self.joint_states_msg = JointState()
        # Without rclpy's default event handlers (they log incompatible QoS), a topic costs
        # the executor nothing; with them, every robot's added several waitables to every
        # turn, and 50 robots' 400 were most of the world's CPU at real time. The node takes
        # the commands at each tick (take_commands), so they never wake its executor.
        self.cmd_vel_sub = node.create_subscription(
            Twist, self.cmd_vel_topic, self.cmd_vel_callback, 10, callback_group=TakenAtTick(),
            event_callbacks=SubscriptionEventCallbacks(use_default_callbacks=False))
        quiet = PublisherEventCallbacks(use_default_callbacks=False)
        if self.odom_topic is not None:
            self.odom_pub = node.create_publisher(Odometry, self.odom_topic, 10,
                                                  event_callbacks=quiet)
            self._publishers[ODOMETRY_STREAM] = (self.publish_odometry,
                                                 SubscriberWatch(self.odom_pub))
        if self.joint_states_topic is not None:
            self.joint_states_pub = node.create_publisher(JointState, self.joint_states_topic, 10,
                                                          event_callbacks=quiet)
            self._publishers[JOINT_STATES_STREAM] = (self.publish_joint_states,
                                                     SubscriberWatch(self.joint_states_pub))

    def publish(self, stream, now):
        """Publish what belongs to a stream that fell due at simulation time now."""
        if stream == ODOMETRY_STREAM and self.encoder_odometry:
            # One arc per odometry period, whether anyone listens or not.
            self.drive.integrate_encoders()
        publish, watch = self._publishers.get(stream, (None, None))
        # Nobody would receive it: skip the message, the costly part.
        if publish is not None and watch.listened():
            publish(now)

    def publish_odometry(self, now):
        """Publish the robot's odometry in its odometry frame (REP 105)."""
        odometry = self.drive.odometry()
        msg = self.odom_msg
        fill_time_msg(msg.header.stamp, now)
        msg.header.frame_id = odometry.odometry_frame
        msg.child_frame_id = odometry.robot_base_frame
        fill_pose_msg(msg.pose.pose, odometry.position, odometry.orientation)
        fill_twist_msg(msg.twist.twist, odometry.linear_velocity, odometry.angular_velocity)
        self.odom_pub.publish(msg)

    def publish_joint_states(self, now):
        """Publish the positions and velocities of the robot's moving joints."""
        self.joint_states_pub.publish(fill_joint_state_msg(
            self.joint_states_msg, now, self.world.joint_state(self.model.name)))

    def take_commands(self):
        """Hand the cmd_vel messages that came since the last tick to the drive, in order."""
        for msg in take_messages(self.cmd_vel_sub):
            self.cmd_vel_callback(msg)

    def cmd_vel_callback(self, msg):
        """Hand a velocity command to the drive; the next steps apply it."""
        name = self.model.name
        try:
            commanded = (finite_number(msg.linear.x, 'linear_x'),
                         finite_number(msg.angular.z, 'angular_z'))
            applied = self.drive.command_velocity(*commanded)
        except WorldError as error:
            self.node.get_logger().warning(
                f'ignored cmd_vel for {name}: {error}', throttle_duration_sec=1.0)
            return
        if tuple(applied) != commanded:
            self.node.get_logger().warning(
                f'cmd_vel for {name} (linear.x {msg.linear.x}, angular.z {msg.angular.z}) '
                f'turns a wheel faster than {MAX_WHEEL_RIM_SPEED} m/s; scaled down to '
                f'linear.x {applied[0]:.4g}, angular.z {applied[1]:.4g}',
                throttle_duration_sec=1.0)

    def destroy(self):
        """Remove the drive's topics from the node."""
        if self.cmd_vel_sub is not None:
            self.node.destroy_subscription(self.cmd_vel_sub)
        for publisher in (self.odom_pub, self.joint_states_pub):
            if publisher is not None:
                self.node.destroy_publisher(publisher)
        self.cmd_vel_sub = self.odom_pub = self.joint_states_pub = None
