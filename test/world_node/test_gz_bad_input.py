"""
gz-sim systems and sensors written wrong, through the world node on simulated time.

A system the world does not simulate is named once in the spawn's answer, and the robot runs.
An absurd parameter (a negative wheel radius, 10^9 lidar samples, NaN noise, a wheel joint
that is not there) refuses the spawn with a message naming the tag. A gz topic that is a valid
gz name but not a valid ROS name is named in an error and not served: the robot spawns and its
other topics work. Meanwhile a robot spawned before keeps driving, and keeps its state.
"""

import math
import os

from geometry_msgs.msg import Twist
import pytest
from rcl_interfaces.msg import Log
from rclpy.node import Node
from repository import read_file, TEST_MODELS
from sensor_msgs.msg import LaserScan
from service_tutorial.world_node.gz_bridge import BridgedTopic, GzBridge, ROS_TO_GZ
from simulation_interfaces.msg import Result
from simulation_interfaces.srv import SpawnEntity

pytestmark = pytest.mark.ros
pytest_plugins = ['service_tutorial.testing.fixtures']

SDF = os.path.join(TEST_MODELS, 'sdf')
PROVING_GROUND = os.path.join(SDF, 'worlds', 'proving_ground.sdf')
SURVEYOR = read_file(os.path.join(SDF, 'models', 'surveyor', 'model.sdf'))
TIMESTEP = 0.001


class Watcher(Node):
    """A user's node: what the world logs on /rosout, and commands for the keeper."""

    def __init__(self, **kwargs):
        super().__init__('gz_watcher', **kwargs)
        self.logged = []
        self.create_subscription(Log, '/rosout', self.logged.append, 1000)
        self.cmd_vel_pub = self.create_publisher(Twist, '/model/keeper/cmd_vel', 10)


@pytest.fixture
def world(mujoco_sim_factory):
    """Start the proving ground with a surveyor named keeper driving at 0.2 m/s."""
    sim = mujoco_sim_factory(world=PROVING_GROUND)
    sim.watcher = sim.add_node(Watcher(context=sim.context))
    sim.spawn_entity('keeper', SURVEYOR, (0.0, -3.0, 0.0))
    assert sim.wait_for(lambda: sim.watcher.cmd_vel_pub.get_subscription_count() > 0)
    forward = Twist()
    forward.linear.x = 0.2
    sim.watcher.cmd_vel_pub.publish(forward)
    sim.step(500)
    return sim


def spawn(world, name, text):
    """Spawn an SDF robot; return the standard's Result."""
    request = SpawnEntity.Request(name=name, resource_string=text)
    request.initial_pose.pose.position.y = 3.0
    return world.call(SpawnEntity, 'spawn_entity', request, timeout=30.0).result


def keeps_driving(world, before):
    """Assert that the keeper drove on from where it was, at 0.2 m/s; return where it is."""
    world.step(500)
    state = world.entity_state('keeper')
    assert state.pose.position.x == pytest.approx(before + 0.1, abs=0.005)
    assert state.twist.linear.x == pytest.approx(0.2, abs=0.01)
    return state.pose.position.x


def with_plugin_text(old, new):
    assert old in SURVEYOR
    return SURVEYOR.replace(old, new)


BAD = [
    ('<wheel_radius>0.05</wheel_radius>', '<wheel_radius>-0.05</wheel_radius>',
     ['DiffDrive <wheel_radius>', 'above 0', '-0.05']),
    ('<samples>181</samples>', '<samples>1000000000</samples>',
     ["sensor 'front_lidar'", 'samples', '1000000000', 'at most 20000']),
    ('<stddev>0.005</stddev>', '<stddev>nan</stddev>', ["sensor 'front_lidar'", 'stddev',
                                                        'nan']),
    ('<left_joint>left_wheel_joint</left_joint>', '<left_joint>left_wheel</left_joint>',
     ['DiffDrive <left_joint>', "'left_wheel'", 'not a joint']),
]


def test_absurd_parameters_refuse_the_spawn_and_the_robot_before_drives_on(world):
    position = world.entity_state('keeper').pose.position.x
    for old, new, words in BAD:
        result = spawn(world, 'newcomer', with_plugin_text(old, new))
        print(f'\n{new}: {result.error_message}')
        assert result.result != Result.RESULT_OK
        for word in words:
            assert word in result.error_message, (word, result.error_message)
        assert 'newcomer' not in world.get_entities()
        position = keeps_driving(world, position)


def test_an_unknown_system_is_named_once_and_the_robot_runs(world):
    text = with_plugin_text('<plugin filename="gz-sim-joint-state-publisher-system"', '''
        <plugin filename="gz-sim-pose-publisher-system" name="gz::sim::systems::PosePublisher">
          <publish_link_pose>true</publish_link_pose>
        </plugin>
        <plugin filename="gz-sim-joint-state-publisher-system"''')
    position = world.entity_state('keeper').pose.position.x
    result = spawn(world, 'newcomer', text)
    assert result.result == Result.RESULT_OK, result.error_message
    print(f'\nan unknown system: {result.error_message}')
    assert result.error_message.count('gz-sim-pose-publisher-system') == 1
    keeps_driving(world, position)
    assert world.entity_state('newcomer').pose.position.z == pytest.approx(0.1, abs=0.01)


def test_a_gz_topic_ros_cannot_take_is_named_and_the_others_work(world):
    text = with_plugin_text('<tf_topic>/tf</tf_topic>',
                            '<tf_topic>/tf</tf_topic><odom_topic>/odom.fast</odom_topic>')
    position = world.entity_state('keeper').pose.position.x
    result = spawn(world, 'newcomer', text)
    assert result.result == Result.RESULT_OK, result.error_message
    assert world.wait_for(lambda: [entry for entry in world.watcher.logged
                                   if entry.level >= Log.ERROR and '/odom.fast' in entry.msg])
    errors = [entry.msg for entry in world.watcher.logged if '/odom.fast' in entry.msg]
    print(f'\n{errors[0]}')
    assert len(errors) == 1 and 'not a valid ROS topic name' in errors[0]
    assert 'not served' in errors[0]
    position = keeps_driving(world, position)
    # Its cmd_vel is served: it drives.
    publisher = world.watcher.create_publisher(Twist, '/model/newcomer/cmd_vel', 10)
    assert world.wait_for(lambda: publisher.get_subscription_count() > 0)
    start = world.entity_state('newcomer').pose.position.x
    forward = Twist()
    forward.linear.x = 0.2
    publisher.publish(forward)
    world.step(500)
    assert world.entity_state('newcomer').pose.position.x - start == pytest.approx(
        0.1 - 0.2 * 0.04 / 2.0, abs=0.005)
    keeps_driving(world, position + 0.1)
    assert not math.isnan(world.entity_state('newcomer').pose.position.y)


def test_a_mapping_of_a_type_that_does_not_go_is_named_and_not_served(world):
    world.world_node.set_gz_bridge(GzBridge([BridgedTopic(
        '/model/newcomer/cmd_vel', 'gz.msgs.Twist', '/newcomer/cmd_vel', LaserScan,
        ROS_TO_GZ)]))
    position = world.entity_state('keeper').pose.position.x
    result = spawn(world, 'newcomer', SURVEYOR)
    assert result.result == Result.RESULT_OK, result.error_message
    assert world.wait_for(lambda: [entry for entry in world.watcher.logged
                                   if '/newcomer/cmd_vel' in entry.msg])
    error, = [entry for entry in world.watcher.logged if '/newcomer/cmd_vel' in entry.msg]
    print(f'\n{error.msg}')
    assert error.level == Log.ERROR and 'LaserScan' in error.msg and 'Twist' in error.msg
    assert world.watcher.count_subscribers('/newcomer/cmd_vel') == 0
    keeps_driving(world, position)
