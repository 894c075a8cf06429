"""
What the world node tells the ROS graph besides its services, through real subscribers.

/clock (also while paused), /tf, robot_description, joint_states, and what it logs on /rosout.
"""

import logging
import signal
import sys
import threading
import time

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import pytest
from rcl_interfaces.msg import Log
import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from repository import read_model, ROOT
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from service_tutorial.conversions import make_pose, seconds_of
from service_tutorial.world_node.log_forwarding import RclpyHandler
from service_tutorial.world_node.node import MujocoWorld
from srv_interfaces.srv import DeleteModel, SpawnModel
from std_msgs.msg import String
from tf2_msgs.msg import TFMessage

pytestmark = pytest.mark.ros

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
# rclpy's own /clock subscription (TimeSource): best effort, volatile, depth 1.
TIME_SOURCE = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT)
# A joint that moves but is no wheel, added to tinybot: joint_states must cover it too.
MAST = ('<link name="mast_link"><inertial><mass value="0.05"/><inertia ixx="1e-4" iyy="1e-4" '
        'izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>'
        '<joint name="mast_joint" type="revolute"><parent link="base_link"/>'
        '<child link="mast_link"/><origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>')


def test_clock_is_transient_local_with_depth_one(ros):
    world = ros.start_world(paused=True)
    qos = world.node.clock_pub.qos_profile
    assert (qos.durability, qos.reliability, qos.depth) == (
        DurabilityPolicy.TRANSIENT_LOCAL, ReliabilityPolicy.RELIABLE, 1)


def test_a_late_subscriber_gets_the_time_within_a_second_while_paused(ros):
    world = ros.start_world(paused=True)
    world.step(150)  # 0.3 s
    paused_at = world.node.world.time
    for qos in (LATCHED, TIME_SOURCE):  # the latched message, then the repeated one
        received = []  # (wall time, simulation time)

        def clock_callback(msg):
            received.append((time.monotonic(), seconds_of(msg.clock)))
        start = time.monotonic()
        subscription = ros.client_node.create_subscription(Clock, '/clock', clock_callback, qos)
        assert ros.wait_for(lambda: received, timeout=1.0), \
            f'no /clock within 1 s for a {qos.durability.name} subscriber'
        wall, sim = received[0]
        assert wall - start <= 1.0 and sim == pytest.approx(paused_at, abs=1e-9)
        ros.destroy(subscription)


def test_a_node_on_sim_time_started_during_a_pause_learns_the_time(ros):
    world = ros.start_world(paused=True)
    world.step(250)  # 0.5 s
    paused_at = world.node.world.time
    late = ros.add_node(Node('late_joiner', parameter_overrides=[
        Parameter('use_sim_time', value=True)]))
    assert ros.wait_for(lambda: late.get_clock().now().nanoseconds > 0, timeout=1.0), \
        'a node on use_sim_time did not learn the time within 1 s'
    assert late.get_clock().now().nanoseconds * 1e-9 == pytest.approx(paused_at, abs=1e-6)


def test_tf_carries_odom_to_base_exactly_as_odom_says(ros):
    # Not free-running, where odom and /tf are also held to their rate in wall time.
    world = ros.start_world(real_time_factor=2.0)
    odometry = ros.subscribe(Odometry, '/odom', depth=1000)
    transforms = ros.subscribe(TFMessage, '/tf', depth=1000)
    assert ros.wait_for(lambda: odometry and transforms), 'no odom or no /tf'
    twist = Twist()
    twist.linear.x, twist.angular.z = 0.3, 0.8  # an arc: x, y and yaw all change
    world.command('/cmd_vel', twist)  # once the world has taken it
    end = world.now() + 1.0
    # Odometry comes on its own subscription, which may lag behind /clock on a busy machine.
    assert ros.wait_for(lambda: seconds_of(odometry[-1].header.stamp) >= end), \
        f'no odometry of {end:.3f} s of simulated time'

    by_stamp = {}
    for message in list(transforms):
        for transform in message.transforms:
            assert (transform.header.frame_id, transform.child_frame_id) == (
                'odom', 'base_footprint')
            by_stamp[seconds_of(transform.header.stamp)] = transform.transform
    matched = 0
    for odom in list(odometry):
        transform = by_stamp.get(seconds_of(odom.header.stamp))
        if transform is None:
            continue
        matched += 1
        pose = odom.pose.pose
        for a, b in ((transform.translation.x, pose.position.x),
                     (transform.translation.y, pose.position.y),
                     (transform.translation.z, pose.position.z),
                     (transform.rotation.x, pose.orientation.x),
                     (transform.rotation.y, pose.orientation.y),
                     (transform.rotation.z, pose.orientation.z),
                     (transform.rotation.w, pose.orientation.w)):
            assert a == pytest.approx(b, abs=1e-6)
    assert matched >= 10, f'only {matched} odom messages had a /tf of the same stamp'
    assert abs(odometry[-1].pose.pose.position.y) > 0.01, 'tinybot did not move'


def test_the_transforms_of_one_turn_go_out_in_one_tf_message(ros):
    world = ros.start_world(real_time_factor=2.0)
    world.spawn_or_fail('tiny', read_model('tinybot'), make_pose(2.0), namespace='tiny')
    transforms = ros.subscribe(TFMessage, '/tf', depth=1000)
    assert ros.wait_for(lambda: any(len(m.transforms) == 2 for m in list(transforms))), \
        'no /tf message carried both robots'
    world.wait_sim(0.2)
    for message in list(transforms):
        assert len(message.transforms) in (1, 2)  # 1: a message sent before the spawn
        stamps = {seconds_of(transform.header.stamp) for transform in message.transforms}
        assert len(stamps) == 1, 'one message, one turn of odometry'


def test_a_drive_whose_block_says_no_sends_no_tf(ros):
    world = ros.start_world(paused=True)
    quiet = read_model('tinybot').replace('<publish_odom_tf>true</publish_odom_tf>',
                                          '<publish_odom_tf>false</publish_odom_tf>')
    world.spawn_or_fail('quiet', quiet, make_pose(2.0), namespace='quiet')
    assert [type(face).__name__ for face in world.node.models['quiet'].faces] == [
        'DriveFace', 'LaserScanFace', 'CameraFace', 'ImuFace']
    assert 'OdomTfFace' in [type(p).__name__ for p in world.node.models['tinybot'].faces]


def test_robot_description_reaches_a_subscriber_that_starts_after_the_world(ros):
    world = ros.start_world(paused=True)
    world.spawn_or_fail('tiny', read_model('tinybot'), make_pose(2.0), namespace='robots/tiny')
    world.spawn_or_fail('r2d2', read_model('r2d2'), make_pose(-2.0))
    world.step(50)
    descriptions = {}
    for topic in ('/robot_description', '/robots/tiny/robot_description'):
        descriptions[topic] = []
        ros.client_node.create_subscription(String, topic, descriptions[topic].append, LATCHED)
    assert ros.wait_for(lambda: all(descriptions.values()), timeout=5.0), descriptions
    for topic, received in descriptions.items():
        assert [msg.data for msg in received] == [read_model('tinybot')], topic
    # R2-D2 has no plugin with topics, so no description; a deleted model takes its own away.
    assert {name for name, interface in world.node.models.items()
            if interface.description is not None} == {'tinybot', 'tiny'}
    response = world.delete('tiny')
    assert response.success, response.status_message
    assert '/robots/tiny/robot_description' not in world.published_topics()


def test_joint_states_cover_every_movable_joint(ros):
    world = ros.start_world(paused=True)
    with_mast = read_model('tinybot').replace('</robot>', MAST)
    world.spawn_or_fail('mast', with_mast, make_pose(2.0), namespace='mast')
    joint_states = ros.subscribe(JointState, '/mast/joint_states')
    world.step(50)
    assert ros.wait_for(lambda: joint_states), 'no joint_states'
    assert sorted(joint_states[-1].name) == [
        'mast_joint', 'wheel_left_joint', 'wheel_right_joint']
    assert len(joint_states[-1].position) == len(joint_states[-1].velocity) == 3


def world_log(ros):
    """Collect what the node named mujoco logs on /rosout, as (level, text)."""
    received = []
    ros.client_node.create_subscription(
        Log, '/rosout', lambda msg: msg.name == 'mujoco' and received.append(
            (msg.level, msg.msg)), QoSProfile(depth=1000))
    return received


def test_a_spawn_and_a_delete_appear_on_rosout_once_each(ros):
    world = ros.start_world(paused=True)
    log = world_log(ros)
    assert ros.wait_for(lambda: world.node.count_subscribers('/rosout') > 0)
    world.spawn_or_fail('r2d2', read_model('r2d2'), make_pose(-2.0))
    response = world.delete('r2d2')
    assert response.success, response.status_message
    spawned = (Log.INFO, "spawned model 'r2d2' at [-2.0, 0.0, 0.0]")
    deleted = (Log.INFO, "deleted model 'r2d2'")
    assert ros.wait_for(lambda: spawned in log and deleted in log, timeout=5.0), log
    world.step(50)
    assert log.count(spawned) == log.count(deleted) == 1


def test_core_logs_reach_rosout_at_their_level(ros):
    world = ros.start_world(paused=True)
    log = world_log(ros)
    core = logging.getLogger('service_tutorial.world')
    assert ros.wait_for(lambda: world.node.count_subscribers('/rosout') > 0)
    for level in (logging.INFO, logging.WARNING, logging.ERROR, logging.INFO):
        core.log(level, 'level %d from the core', level)
    expected = [(Log.INFO, 'level 20 from the core'), (Log.WARN, 'level 30 from the core'),
                (Log.ERROR, 'level 40 from the core'), (Log.INFO, 'level 20 from the core')]
    assert ros.wait_for(lambda: log[-4:] == expected, timeout=5.0), log


# The world in a process whose logger class was installed before the package was imported:
# launch's, whose loggers do not propagate (launch.logging; launch_testing's pytest plugin imports
# it in every pytest run on a Jazzy install), or where launch is missing a class doing the same.
# The root logger gets a handler of the application's own, as caplog's or basicConfig's.
WORLD_UNDER_A_LOGGER_CLASS = """
import logging
import sys

if sys.argv[1] == 'launch':
    import launch.logging
    assert logging.getLoggerClass() is launch.logging.LaunchLogger
else:
    class NotPropagating(logging.getLoggerClass()):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            self.propagate = False
    logging.setLoggerClass(NotPropagating)
logging.basicConfig(format='root logger: %(message)s')
from service_tutorial.world_node.node import main
main()
"""


class Listener:
    """A subscription on a DDS participant (rclpy context) of its own, spun in a thread."""

    def __init__(self, msg_type, topic, callback, qos):
        """Subscribe to topic from now on."""
        self.context = Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node('rosout_listener', context=self.context)
        self.node.create_subscription(msg_type, topic, callback, qos)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        try:
            self.executor.spin()
        except ExternalShutdownException:  # close()
            pass

    def close(self):
        """Stop spinning and leave the graph."""
        self.context.try_shutdown()
        self.thread.join(timeout=30.0)
        self.executor.shutdown()
        self.node.destroy_node()


@pytest.mark.parametrize('logger_class', ['launch', 'not propagating'])
def test_the_worlds_logs_reach_rosout_and_the_root_whatever_the_logger_class(
        ros, start_program, logger_class):
    if logger_class == 'launch':
        pytest.importorskip('launch.logging', reason='launch is not installed (not on PyPI)')
    log = []
    # Transient local: also what came before it matched, for /rosout's lifespan of 10 s. On a
    # participant of its own, which matches a new world at once, where the long run's one takes
    # longer than that after a whole suite's endpoints.
    listener = Listener(
        Log, '/rosout', lambda msg: msg.name == 'mujoco' and log.append((msg.level, msg.msg)),
        QoSProfile(depth=1000, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    world = start_program([sys.executable, '-c', WORLD_UNDER_A_LOGGER_CLASS, logger_class],
                          cwd=ROOT)
    try:
        request = SpawnModel.Request(model_name='r2d2', model_xml=read_model('r2d2'))
        response = ros.call(SpawnModel, '/mujoco/spawn_urdf_model', request, timeout=60.0)
        assert response.success, response.status_message
        response = ros.call(DeleteModel, '/mujoco/delete_model',
                            DeleteModel.Request(model_name='r2d2'))
        assert response.success, response.status_message
        logged = ["spawned model 'tinybot' at [0.0, 0.0, 0.0]",  # at start-up
                  "spawned model 'r2d2' at [0.0, 0.0, 0.0]", "deleted model 'r2d2'"]
        expected = [(Log.INFO, text) for text in logged]
        assert ros.wait_for(lambda: [entry for entry in log if entry[1] in logged] == expected,
                            timeout=5.0), log
    finally:
        world.send_signal(signal.SIGINT)
        stderr = world.communicate(timeout=30.0)[1]
        listener.close()
    assert world.returncode == 0, stderr
    root = [line for line in stderr.splitlines() if line.startswith('root logger: ')]
    assert root == [f'root logger: {text}' for text in logged], stderr


def test_the_log_handler_leaves_with_the_node(rclpy_session):
    core = logging.getLogger('service_tutorial')

    def handlers():
        return [handler for handler in core.handlers if isinstance(handler, RclpyHandler)]
    level = core.level
    world = MujocoWorld()
    try:
        assert len(handlers()) == 1 and core.getEffectiveLevel() == logging.INFO
    finally:
        world.destroy_node()
    assert handlers() == [] and core.level == level


def spawn_r2d2(ros, namespace, *, tries=6):
    """
    Spawn R2-D2 into a world just started, asking again if no answer comes.

    A world just started can answer before it has matched the caller's response reader, and
    that answer is lost (CI saw Fast DDS's 'failed to send response (timeout)'). Asked again,
    the world says R2-D2 exists when the first request did spawn it.
    """
    service = f'{namespace}/mujoco/spawn_urdf_model'
    waiting = ros.client_node.create_client(SpawnModel, service)
    try:
        assert waiting.wait_for_service(timeout_sec=60.0), f'no {service}'
    finally:
        ros.destroy(waiting)
    request = SpawnModel.Request(model_name='r2d2', model_xml=read_model('r2d2'))
    for attempt in range(tries):
        try:
            response = ros.call(SpawnModel, service, request, timeout=5.0)
        except AssertionError:
            if attempt == tries - 1:
                raise
            continue
        assert response.success or (attempt > 0 and 'already exists' in response.status_message), \
            response.status_message
        return


@pytest.mark.parametrize('real_time_factor', [0.0, 1.0])
@pytest.mark.long
def test_a_stop_signal_ends_the_world_quietly_whatever_it_was_doing(
        ros, start_program, real_time_factor):
    # SIGTERM (docker stop, launch after a SIGINT) shuts the context down under the step
    # callback, mostly while it publishes; SIGINT too, in a program started where it is ignored.
    # Three worlds, started at once, each in a namespace of its own with its /clock there too:
    # each is stopped at another moment of its steps.
    namespaces = [f'/stopped_{int(real_time_factor)}_{start}' for start in range(3)]
    worlds = {namespace: start_program(
        [sys.executable, '-m', 'service_tutorial.world_node.node', '--ros-args',
         '-r', f'__ns:={namespace}', '-r', f'/clock:={namespace}/clock',
         '-p', f'real_time_factor:={real_time_factor}'], cwd=ROOT) for namespace in namespaces}
    for namespace, world in worlds.items():
        clock = []
        ros.client_node.create_subscription(Clock, f'{namespace}/clock', clock.append,
                                            TIME_SOURCE)
        try:
            spawn_r2d2(ros, namespace)
            clock.clear()
            assert ros.wait_for(lambda: len(clock) >= 20), 'the world does not step'
        finally:
            world.send_signal(signal.SIGTERM)
            stderr = world.communicate(timeout=30.0)[1]
            print(f'the world in {namespace} wrote:', stderr, sep='\n')
        assert world.returncode == 0 and 'Traceback' not in stderr, stderr
