"""
The ROS face of one model in the world: the turtle of turtlesim.

The world node makes a ModelInterface when it spawns a model and destroys it along with the
model. The interface keeps the model's ROS namespace and gives each plugin of the model its
topics under it; today that is the diff drive (cmd_vel in, odom and joint_states out, like
gazebo_ros_diff_drive). A sensor is one more small class in PLUGIN_INTERFACES: a class method
applies_to(world, model_name), publish(stream, now) for the node's publication streams, and
destroy().
"""

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import JointState
from service_tutorial.conversions import fill_pose_msg, fill_time_msg, fill_twist_msg
from service_tutorial.pacing import JOINT_STATES_STREAM, ODOMETRY_STREAM
from service_tutorial.ros_names import topic_prefix
from service_tutorial.sensor_interfaces import SENSOR_INTERFACES
from service_tutorial.sim.plugins.diff_drive import MAX_WHEEL_RIM_SPEED
from service_tutorial.sim.validation import WorldError
from service_tutorial.tf_interface import OdomTfInterface


class DiffDriveInterface:
    """A diff drive's topics: cmd_vel in, odom and joint_states out."""

    @classmethod
    def applies_to(cls, world, model_name):
        """Tell whether the model carries a diff drive."""
        return model_name in world.diff_drive_models()

    def __init__(self, node, world, model_name, prefix):
        self.node = node
        self.world = world
        self.model_name = model_name
        self.cmd_vel_sub = node.create_subscription(
            Twist, prefix + 'cmd_vel', self.cmd_vel_callback, 10)
        self.odom_pub = node.create_publisher(Odometry, prefix + 'odom', 10)
        self.joint_states_pub = node.create_publisher(JointState, prefix + 'joint_states', 10)
        # Filled in and published again every time: publish() copies the message.
        self.odom_msg = Odometry()
        self.joint_states_msg = JointState()
        self._publishers = {ODOMETRY_STREAM: self.publish_odometry,
                            JOINT_STATES_STREAM: self.publish_joint_states}

    def publish(self, stream, now):
        """Publish what belongs to a stream that fell due at simulation time now."""
        publish = self._publishers.get(stream)
        if publish is not None:
            publish(now)

    def publish_odometry(self, now):
        """Publish the robot's odometry in its odometry frame (REP 105)."""
        odometry = self.world.odometry(self.model_name)  # integrates the encoders, always
        if self.odom_pub.get_subscription_count() == 0:
            return  # nobody would receive it: skip the message, the costly part
        msg = self.odom_msg
        fill_time_msg(msg.header.stamp, now)
        msg.header.frame_id = odometry.odometry_frame
        msg.child_frame_id = odometry.robot_base_frame
        fill_pose_msg(msg.pose.pose, odometry.position, odometry.orientation)
        fill_twist_msg(msg.twist.twist, odometry.linear_velocity, odometry.angular_velocity)
        self.odom_pub.publish(msg)

    def publish_joint_states(self, now):
        """Publish the positions and velocities of the robot's moving joints."""
        if self.joint_states_pub.get_subscription_count() == 0:
            return
        names, positions, velocities = self.world.joint_state(self.model_name)
        msg = self.joint_states_msg
        fill_time_msg(msg.header.stamp, now)
        msg.name = names
        msg.position = positions.tolist()
        msg.velocity = velocities.tolist()
        self.joint_states_pub.publish(msg)

    def cmd_vel_callback(self, msg):
        """Hand a velocity command to the world; the next steps apply it."""
        name = self.model_name
        try:
            applied = self.world.command_velocity(name, msg.linear.x, msg.angular.z)
        except WorldError as error:
            self.node.get_logger().warning(
                f'ignored cmd_vel for {name}: {error}', throttle_duration_sec=1.0)
            return
        if applied != (msg.linear.x, msg.angular.z):
            self.node.get_logger().warning(
                f'cmd_vel for {name} (linear.x {msg.linear.x}, angular.z {msg.angular.z}) '
                f'turns a wheel faster than {MAX_WHEEL_RIM_SPEED} m/s; scaled down to '
                f'linear.x {applied[0]:.4g}, angular.z {applied[1]:.4g}',
                throttle_duration_sec=1.0)

    def destroy(self):
        """Remove the drive's topics from the node."""
        self.node.destroy_subscription(self.cmd_vel_sub)
        self.node.destroy_publisher(self.odom_pub)
        self.node.destroy_publisher(self.joint_states_pub)


# Every kind of plugin that has a ROS face, in the order their topics are made.
PLUGIN_INTERFACES = (DiffDriveInterface, OdomTfInterface) + SENSOR_INTERFACES


class ModelInterface:
    """One model's namespace and the topics of each of its plugins."""

    def __init__(self, node, world, model_name, namespace):
        """Give a model just spawned its topics; namespace is normalised ('' or '/a/b')."""
        self.model_name = model_name
        self.namespace = namespace
        self.plugins = []
        try:
            for kind in PLUGIN_INTERFACES:
                if kind.applies_to(world, model_name):
                    self.plugins.append(kind(node, world, model_name, topic_prefix(namespace)))
        except Exception:
            self.destroy()
            raise

    def publish(self, stream, now):
        """Publish each plugin's part of a stream that fell due at simulation time now."""
        for plugin in self.plugins:
            plugin.publish(stream, now)

    def destroy(self):
        """Remove every topic of the model from the node."""
        for plugin in self.plugins:
            plugin.destroy()
        self.plugins = []
