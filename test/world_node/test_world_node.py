"""
The MuJoCo world node through its real services and topics, as a ROS user meets it.

The world starts paused and time moves by whole steps (RunningWorld.step), so what a test
asserts does not depend on how fast the machine is; a test of pausing a playing world, and one
of /clock at either pace, let it play.
"""

import math

from geometry_msgs.msg import Pose, Twist
from nav_msgs.msg import Odometry
import pytest
from repository import read_model
from running_world import lesson_pose
from sensor_msgs.msg import JointState
from service_tutorial.conversions import make_pose, seconds_of as seconds, yaw_of
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_robot
from srv_interfaces.srv import SetModelState

pytestmark = pytest.mark.ros


def resting_height_of_r2d2():
    """Where R2-D2's base ends up after a long drop in a world of its own."""
    world = World()
    spawn_robot(world, 'r2d2', read_model('r2d2'), position=(0, 0, 1))
    world.step(int(5.0 / world.timestep))
    return world.get_model_state('r2d2').position[2]


def test_default_world_holds_tinybot_and_publishes_clock(paused_world):
    assert paused_world.models() == ['tinybot']
    start = paused_world.now()
    assert paused_world.step(250) == pytest.approx(start + 0.5, abs=1e-9)


def test_spawned_r2d2_comes_to_rest_on_the_ground_with_the_lesson_heading(paused_world):
    response = paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose())
    assert response.success, response.status_message
    assert 'r2d2' in response.status_message
    assert paused_world.models() == ['tinybot', 'r2d2']

    paused_world.step(1000)  # 2 s
    state = paused_world.state('r2d2')
    assert state.success, state.status_message
    assert state.pose.position.x == pytest.approx(-2.0, abs=0.02)
    assert state.pose.position.y == pytest.approx(1.0, abs=0.02)
    assert state.pose.position.z == pytest.approx(resting_height_of_r2d2(), abs=0.01)
    assert yaw_of(state.pose.orientation) == pytest.approx(-math.pi / 2, abs=0.03)
    assert abs(state.twist.linear.z) < 0.01
    assert state.header.frame_id == 'world'


def test_duplicate_spawn_fails_and_delete_works_once(paused_world):
    assert paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose()).success
    again = paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose())
    assert not again.success
    assert "'r2d2'" in again.status_message and 'exists' in again.status_message

    deleted = paused_world.delete('r2d2')
    assert deleted.success, deleted.status_message
    assert paused_world.models() == ['tinybot']
    twice = paused_world.delete('r2d2')
    assert not twice.success
    assert "'r2d2'" in twice.status_message


def test_cmd_vel_turns_tinybot_by_the_commanded_angle(paused_world, ros):
    odometry = ros.subscribe(Odometry, '/odom')
    joint_states = ros.subscribe(JointState, '/joint_states')
    paused_world.step()  # the state streams go out where steps end
    assert odometry and joint_states
    before = paused_world.state('tinybot')
    odom_before = yaw_of(odometry[-1].pose.pose.orientation)

    twist = Twist()
    twist.angular.z = 0.5
    paused_world.drive({'/cmd_vel': twist}, 2.0)

    after = paused_world.state('tinybot')
    turned = yaw_of(after.pose.orientation) - yaw_of(before.pose.orientation)
    odom_turned = yaw_of(odometry[-1].pose.pose.orientation) - odom_before
    print(f'\ncmd_vel angular.z 0.5 for 2.0 s: turned {turned:.4f} rad (ground truth), '
          f'{odom_turned:.4f} rad (/odom)')
    assert turned == pytest.approx(1.0, rel=0.03)
    assert odom_turned == pytest.approx(1.0, rel=0.03)
    assert odometry[-1].header.frame_id == 'odom'
    assert odometry[-1].child_frame_id in ('base_footprint', 'base_link')
    assert len(joint_states[-1].name) >= 2
    assert abs(after.twist.angular.z) < 0.02, 'tinybot kept turning after the zero Twist'


def test_cmd_vel_drives_tinybot_forward_by_the_commanded_distance(paused_world, ros):
    odometry = ros.subscribe(Odometry, '/odom')
    paused_world.step()
    assert odometry
    before = paused_world.state('tinybot').pose.position
    odom_before = odometry[-1].pose.pose.position

    twist = Twist()
    twist.linear.x = 0.2
    paused_world.drive({'/cmd_vel': twist}, 2.0)

    after = paused_world.state('tinybot').pose.position
    moved = math.hypot(after.x - before.x, after.y - before.y)
    odom_after = odometry[-1].pose.pose.position
    odom_moved = math.hypot(odom_after.x - odom_before.x, odom_after.y - odom_before.y)
    print(f'\ncmd_vel linear.x 0.2 for 2.0 s: moved {moved:.4f} m (ground truth), '
          f'{odom_moved:.4f} m (/odom)')
    assert moved == pytest.approx(0.4, rel=0.03)
    assert odom_moved == pytest.approx(0.4, rel=0.03)
    assert after.x > before.x


def test_reset_world_restores_poses_while_the_clock_goes_on(paused_world, ros):
    assert paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose()).success
    moved = Pose()
    moved.position.x, moved.position.y, moved.orientation.w = 1.5, -0.5, 1.0
    response = ros.call(SetModelState, '/mujoco/set_model_state', SetModelState.Request(
        model_name='tinybot', pose=moved, reference_frame='world'))
    assert response.success, response.status_message
    paused_world.step(500)  # 1 s
    assert paused_world.state('tinybot').pose.position.x == pytest.approx(1.5, abs=0.01)

    clock_before = paused_world.now()
    paused_world.empty('reset_world')
    tinybot = paused_world.state('tinybot')
    r2d2 = paused_world.state('r2d2')
    assert tinybot.pose.position.x == pytest.approx(0.0, abs=0.01)
    assert tinybot.pose.position.y == pytest.approx(0.0, abs=0.01)
    assert r2d2.pose.position.z == pytest.approx(1.0, abs=0.05)
    assert paused_world.models() == ['tinybot', 'r2d2']
    assert seconds(r2d2.header.stamp) >= clock_before, 'reset_world moved the clock back'
    # The clock goes on from where it was.
    assert paused_world.step(50) == pytest.approx(clock_before + 0.1, abs=1e-9)


def test_reset_simulation_also_sets_the_clock_back_to_zero(paused_world):
    assert paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose()).success
    paused_world.step(750)  # 1.5 s
    paused_world.empty('reset_simulation')
    state = paused_world.state('r2d2')
    assert seconds(state.header.stamp) == 0.0
    assert state.pose.position.z == pytest.approx(1.0, abs=1e-6)
    assert paused_world.ros.wait_for(lambda: paused_world.now() == 0.0)
    assert paused_world.models() == ['tinybot', 'r2d2']
    # Time goes on from zero.
    assert paused_world.step(100) == pytest.approx(0.2, abs=1e-9)


def test_pause_physics_stops_simulation_time(fast_world):
    fast_world.empty('pause_physics')
    paused_at = fast_world.state('tinybot').header.stamp
    fast_world.wait_ticks(10)  # ten chances to step, every one of them passed up
    assert fast_world.state('tinybot').header.stamp == paused_at
    fast_world.empty('unpause_physics')
    fast_world.wait_sim(0.1)


def test_state_in_a_model_frame_and_in_a_link_frame(paused_world):
    assert paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose()).success
    paused_world.step(100)
    world_state = paused_world.state('r2d2')
    relative = paused_world.state('r2d2', frame='tinybot')
    assert relative.success, relative.status_message
    tinybot = paused_world.state('tinybot').pose.position
    # tinybot has not turned, so the offset is the same in both frames.
    assert relative.pose.position.x == pytest.approx(world_state.pose.position.x - tinybot.x,
                                                     abs=1e-3)
    assert relative.header.frame_id == 'tinybot'
    assert paused_world.state('r2d2', frame='tinybot::base_link').success


def test_every_model_gets_a_ros_interface_under_its_namespace(paused_world):
    node = paused_world.node
    spawned = paused_world.spawn('tiny', read_model('tinybot'), make_pose(2.0),
                                 namespace='robots/tiny/')
    assert spawned.success, spawned.status_message
    assert paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose()).success
    assert list(node.models) == ['tinybot', 'tiny', 'r2d2']
    assert node.models['tiny'].namespace == '/robots/tiny'
    assert node.models['tinybot'].namespace == node.models['r2d2'].namespace == ''
    tiny_topics = {'/robots/tiny/cmd_vel', '/robots/tiny/odom', '/robots/tiny/joint_states'}
    assert tiny_topics | {'/cmd_vel', '/odom', '/joint_states'} <= paused_world.topics()
    assert not node.models['r2d2'].faces, 'R2-D2 has no plugin with a ROS face'
    assert paused_world.delete('tiny').success
    assert list(node.models) == ['tinybot', 'r2d2']
    assert not tiny_topics & paused_world.topics()


BAD_SPAWNS = [
    ('', read_model('tinybot'), Pose(), 'world', 'empty'),
    ('tinybot', read_model('tinybot'), Pose(), 'world', 'exists'),
    ('broken', '<robot name="broken"><link name="a">', Pose(), 'world', 'XML'),
    ('sdf', '<sdf version="1.6"><model name="m"/></sdf>', Pose(), 'world', 'URDF'),
    ('lost', read_model('tinybot'), Pose(), 'nowhere', "'nowhere'"),
]


def bad_pose(**orientation):
    pose = Pose()
    pose.position.z = 0.5
    for axis, value in orientation.items():
        setattr(pose.orientation, axis, value)
    return pose


def test_every_refusal_names_its_cause_and_changes_nothing(paused_world):
    assert paused_world.spawn('r2d2', read_model('r2d2'), lesson_pose()).success
    paused_world.step(150)
    before = {name: paused_world.state(name) for name in paused_world.models()}

    nan_position = Pose()
    nan_position.position.x = math.nan
    refusals = BAD_SPAWNS + [
        ('zero_q', read_model('tinybot'), bad_pose(w=0.0), 'world', 'zero'),
        ('nan_q', read_model('tinybot'), bad_pose(w=math.nan), 'world', 'NaN'),
        ('nan_p', read_model('tinybot'), nan_position, 'world', 'NaN'),
    ]
    for name, xml, pose, frame, cause in refusals:
        response = paused_world.spawn(name, xml, pose, frame)
        assert not response.success, f'{name!r} was spawned'
        assert cause.lower() in response.status_message.lower(), response.status_message

    unknown = [
        paused_world.delete('ghost'),
        paused_world.state('ghost'),
        paused_world.state('r2d2', frame='ghost'),
        paused_world.set_state('ghost', lesson_pose()),
        paused_world.set_state('r2d2', bad_pose(w=0.0)),
    ]
    for response in unknown:
        assert not response.success
        assert "'ghost'" in response.status_message or 'zero' in response.status_message

    assert paused_world.models() == list(before)
    for name, state in before.items():
        now = paused_world.state(name)
        assert now.pose == state.pose, f'{name} moved'
        assert now.twist == state.twist, f'{name} changed speed'
        assert now.header.stamp == state.header.stamp, 'time went on while paused'


@pytest.mark.parametrize('factor', [0.0, 1.0])
def test_clock_goes_forward_in_whole_steps_at_most_at_its_rate(ros, factor):
    # How fast each pace runs is the benchmark's business (its free_running and real_time
    # tables); here, what /clock says at either pace.
    world = ros.start_world(real_time_factor=factor)
    world.wait_sim(1.0)
    stamps = [stamp for _, stamp in list(world.clock)]
    steps = [stamp / world.node.world.timestep for stamp in stamps]
    assert all(abs(step - round(step)) < 1e-6 for step in steps), 'a stamp between two steps'
    # 250 Hz of simulation time at the most (half a step of slack), never backwards.
    assert all(later - earlier > 0.004 - 0.001 for earlier, later in zip(stamps, stamps[1:]))
    # wait_sim() ends at the first stamp plus 1.0, which, less that stamp, can come out a
    # rounding below 1.0 (1.436 - 0.436).
    assert stamps[-1] - stamps[0] >= 1.0 - 1e-9


def test_a_model_deleted_before_its_topics_are_made_leaves_none_behind(rclpy_session):
    from rclpy.parameter import Parameter
    from service_tutorial.world_node.node import MujocoWorld
    # Not spun: the test plays the executor, making the topics when it says.
    node = MujocoWorld(parameter_overrides=[Parameter('paused', value=True)])
    try:
        def topics():
            publishers = list(node.publishers) + node.sensor_node.publishers
            return ({publisher.topic_name for publisher in publishers}
                    | {subscription.topic_name for subscription in node.subscriptions})

        tiny = SpawnOrder('tiny', read_model('tinybot'), position=(2.0, 0.0, 0.0))
        assert node.spawn_models([tiny], ['tiny']) == ['']
        assert not {topic for topic in topics() if topic.startswith('/tiny/')}, \
            'the topics are made once the spawn is answered'
        node.delete_model('tiny')
        assert node.spawn_models([tiny], ['other']) == ['']
        node.make_model_topics()
        # The first 'tiny' left before its topics were made; the second has its own only.
        assert not {topic for topic in topics() if topic.startswith('/tiny/')}
        assert {'/other/cmd_vel', '/other/odom', '/other/scan'} <= topics()
        assert list(node.models) == ['tinybot', 'tiny'] == node.world.model_names()
    finally:
        node.destroy_node()
