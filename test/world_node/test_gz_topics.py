"""
gz-sim's systems and sensors on their ROS topics, as ros_gz_bridge serves them, in sim time.

The world is the suite's SDF world test/models/sdf/worlds/proving_ground.sdf (its origin on
the Earth, a wall at x = 2 m); the suite's own robots with gz-sim blocks (surveyor, an SDF
model; gzbot, a URDF; burger, a TurtleBot3 Burger-like SDF) are spawned into it, paused, and
stepped through the deterministic fixture (service_tutorial.testing): every topic is the gz
topic of the same name with the bridge's default ROS type, or what a GzBridge mapping says.
"""

import math
import os

from geometry_msgs.msg import Twist, TwistStamped
from nav_msgs.msg import Odometry
import numpy as np
import pytest
from rclpy.node import Node
from repository import read_file, TEST_MODELS
from sensor_msgs.msg import JointState
from service_tutorial.conversions import seconds_of
from service_tutorial.world_node.gz_bridge import BridgedTopic, GzBridge, ROS_TO_GZ
from tf2_msgs.msg import TFMessage

pytestmark = pytest.mark.ros
pytest_plugins = ['service_tutorial.testing.fixtures']

SDF = os.path.join(TEST_MODELS, 'sdf')
PROVING_GROUND = os.path.join(SDF, 'worlds', 'proving_ground.sdf')
SURVEYOR = os.path.join(SDF, 'models', 'surveyor', 'model.sdf')
BURGER = os.path.join(SDF, 'models', 'burger', 'model.sdf')
GZBOT = os.path.join(TEST_MODELS, 'gzbot.urdf')
TIMESTEP = 0.001  # the world's max_step_size


def steps(seconds):
    return round(seconds / TIMESTEP)


class Listener(Node):
    """A user's node: keeps what comes on topics, and publishes commands."""

    def __init__(self, **kwargs):
        super().__init__('gz_listener', **kwargs)
        self.received = {}

    def listen(self, msg_type, topic):
        """Keep every message of a topic from now on; return their list."""
        received = self.received.setdefault(topic, [])
        self.create_subscription(msg_type, topic, received.append, 10)
        return received


@pytest.fixture
def world(mujoco_sim_factory):
    """Start the proving ground, paused, with a listener node."""
    sim = mujoco_sim_factory(world=PROVING_GROUND)
    sim.listener = sim.add_node(Listener(context=sim.context))
    return sim


def spawn(world, name, path, pose=(0.0, 0.0, 0.0)):
    world.spawn_entity(name, read_file(path), pose)
    world.step(steps(0.3))  # the robot settles on its wheels


def command(world, topic, msg_type, linear_x):
    publisher = world.listener.create_publisher(msg_type, topic, 10)
    assert world.wait_for(lambda: publisher.get_subscription_count() > 0)
    msg = msg_type()
    (msg.twist if msg_type is TwistStamped else msg).linear.x = linear_x
    publisher.publish(msg)


def drive_for_a_second(world, name, topic, msg_type):
    """Command 0.2 m/s on a topic for 1 s of simulation time; return the distance travelled."""
    start = world.entity_state(name).pose.position
    command(world, topic, msg_type, 0.2)
    world.step(steps(1.0))
    end = world.entity_state(name).pose.position
    return math.hypot(end.x - start.x, end.y - start.y)


@pytest.mark.parametrize('name, path, cmd_vel', [
    ('surveyor', SURVEYOR, '/model/surveyor/cmd_vel'), ('gzbot', GZBOT, '/cmd_vel')])
def test_robots_drive_on_their_gz_cmd_vel_as_twist(world, name, path, cmd_vel):
    spawn(world, name, path)
    travelled = drive_for_a_second(world, name, cmd_vel, Twist)
    print(f'\n{name}: 0.2 m/s on {cmd_vel} (Twist) for 1 s travelled {travelled:.4f} m')
    assert 0.19 <= travelled <= 0.21


@pytest.mark.parametrize('name, path, cmd_vel', [
    ('surveyor', SURVEYOR, '/model/surveyor/cmd_vel'), ('gzbot', GZBOT, '/cmd_vel')])
def test_a_bridge_mapping_makes_cmd_vel_twist_stamped(world, name, path, cmd_vel):
    world.world_node.gz_bridge = GzBridge([BridgedTopic(
        cmd_vel, 'gz.msgs.Twist', 'cmd_vel_stamped', TwistStamped, ROS_TO_GZ)])
    spawn(world, name, path)
    assert world.listener.count_subscribers(cmd_vel) == 0
    travelled = drive_for_a_second(world, name, '/cmd_vel_stamped', TwistStamped)
    print(f'\n{name}: 0.2 m/s on /cmd_vel_stamped (TwistStamped) for 1 s travelled '
          f'{travelled:.4f} m')
    assert 0.19 <= travelled <= 0.21


@pytest.mark.parametrize('name, path, topics, frames', [
    ('surveyor', SURVEYOR,
     ('/world/proving_ground/model/surveyor/joint_state', '/model/surveyor/odometry', '/tf'),
     ('odom', 'chassis')),
    ('gzbot', GZBOT, ('/joint_states', '/odom', '/tf'), ('odom', 'base_footprint'))])
def test_joint_states_odometry_and_tf_in_the_declared_frames(world, name, path, topics,
                                                             frames):
    spawn(world, name, path)
    joint_topic, odom_topic, tf_topic = topics
    joints = world.listener.listen(JointState, joint_topic)
    odometry = world.listener.listen(Odometry, odom_topic)
    transforms = world.listener.listen(TFMessage, tf_topic)
    command(world, '/model/surveyor/cmd_vel' if name == 'surveyor' else '/cmd_vel', Twist, 0.2)
    world.step(steps(1.0))
    assert joints and odometry and transforms
    state = joints[-1]
    assert list(state.name) == ['left_wheel_joint', 'right_wheel_joint']
    radius = 0.05 if name == 'surveyor' else 0.04
    assert state.velocity == pytest.approx([0.2 / radius] * 2, rel=0.05)
    assert len(state.effort) == 2
    odom = odometry[-1]
    assert (odom.header.frame_id, odom.child_frame_id) == frames
    assert seconds_of(odom.header.stamp) == pytest.approx(world.time, abs=0.04)
    assert odom.pose.pose.position.x == pytest.approx(0.195, abs=0.01)
    assert odom.twist.twist.linear.x == pytest.approx(0.2, abs=0.01)
    transform = transforms[-1].transforms[0]
    assert (transform.header.frame_id, transform.child_frame_id) == frames
    assert transform.transform.translation.x == pytest.approx(0.195, abs=0.01)
    # Odometry at its frequency: surveyor's default 50 Hz, gzbot's 30 Hz.
    period = 0.02 if name == 'surveyor' else 1.0 / 30.0
    stamps = [seconds_of(msg.header.stamp) for msg in odometry]
    assert np.diff(stamps) == pytest.approx([period] * (len(stamps) - 1), abs=TIMESTEP * 1.01)
