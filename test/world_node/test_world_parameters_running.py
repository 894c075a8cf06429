"""
The world node's parameters on a running world: what a value given to it does to it.

Values are given at start-up or set at run time through the node's set_parameters service, as
`ros2 param set` does, and their effect is measured on the running world. What each parameter
is and which values it refuses, where no world runs, is test_world_parameters_declared's part.
"""

import math
import os
import statistics

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from PIL import Image as PillowImage
import pytest
from sensor_msgs.msg import CameraInfo, Image
from service_tutorial.conversions import seconds_of
from std_srvs.srv import Trigger

pytestmark = pytest.mark.ros


def measured_pace(world, wall_seconds=2.0, span=0.5):
    """
    Measure simulated seconds per wall second on /clock over the next wall_seconds.

    The median of the paces over every span of wall time in it: on a busy machine a message
    may reach the test late, or the world may make up a stall, and a pace taken between the
    first and the last message alone moved by a tenth with the delay of either.
    """
    start = len(world.clock)
    assert world.ros.wait_for(lambda: len(world.clock) > start)
    first = world.clock[start]
    assert world.ros.wait_for(lambda: world.clock[-1][0] - first[0] >= wall_seconds,
                              timeout=wall_seconds + 10.0), '/clock stopped'
    samples = world.clock[start:]
    paces, end = [], 0
    for wall, sim in samples:
        while end < len(samples) and samples[end][0] - wall < span:
            end += 1
        if end == len(samples):
            break
        paces.append((samples[end][1] - sim) / (samples[end][0] - wall))
    assert len(paces) >= 10, f'{len(samples)} /clock messages in {wall_seconds} s'
    return statistics.median(paces)


def stamp(world):
    """Return the simulation time of tinybot's state, as get_model_state answers it."""
    return seconds_of(world.state('tinybot').header.stamp)


def test_every_writable_parameter_is_followed_by_the_running_world(ros):
    world = ros.start_world()
    assert world.node.parameters.unwatched() == []


@pytest.mark.parametrize('factor, low, high', [
    (2, 1.8, 2.2),        # twice real time, within 10 %; given as an integer, as -p 2 gives it
    (0, 5.0, math.inf),   # free-running: far faster than real time, as fast as it can
])
def test_real_time_factor_given_at_start_up_sets_the_pace(ros, factor, low, high):
    world = ros.start_world(real_time_factor=factor)
    pace = measured_pace(world)
    print(f'\nreal_time_factor {factor}: {pace:.2f} simulated seconds per wall second')
    assert low <= pace <= high


def test_real_time_factor_set_at_run_time_changes_the_pace_at_once(ros):
    world = ros.start_world(real_time_factor=1.0)
    paces = {}
    for factor in (2, 0.0, 1.0):  # 2 as an integer, as `ros2 param set /mujoco ... 2` sends it
        result = ros.set_parameter('mujoco', 'real_time_factor', factor)
        assert result.successful, result.reason
        if factor == 2:
            assert ros.get_parameter('mujoco', 'real_time_factor').double_value == 2.0
            assert world.node.pacer.real_time_factor == 2.0
        paces[factor] = measured_pace(world)
    print(f'\nmeasured paces after each set: {paces}')
    assert 1.8 <= paces[2.0] <= 2.2
    assert paces[0.0] >= 5.0
    assert 0.9 <= paces[1.0] <= 1.1


def test_paused_follows_the_parameter_and_the_services_both_ways(ros):
    world = ros.start_world(real_time_factor=0.0)
    assert ros.set_parameter('mujoco', 'paused', True).successful
    paused_at = stamp(world)
    world.wait_ticks(10)  # ten chances to step, every one of them passed up
    assert stamp(world) == paused_at and world.node.world.paused
    assert ros.set_parameter('mujoco', 'paused', False).successful
    world.wait_sim(0.2)
    assert stamp(world) > paused_at

    world.empty('pause_physics')
    assert ros.get_parameter('mujoco', 'paused').bool_value is True
    paused_at = stamp(world)
    world.empty('unpause_physics')
    assert ros.get_parameter('mujoco', 'paused').bool_value is False
    world.wait_sim(0.2)
    assert stamp(world) > paused_at


@pytest.mark.parametrize('name, value, words', [
    ('real_time_factor', -1.0, ['real_time_factor', '-1.0']),
    ('clock_publish_rate', 0.0, ['clock_publish_rate:=0.0', '> 0.0']),
    ('cmd_vel_timeout', 'long', ['type', 'DOUBLE', 'STRING']),  # rclpy's own words
    ('camera_fovy', 180.0, ['camera_fovy:=180.0', '< 180.0']),
    ('timestep', 0.001, ['timestep', 'read-only']),
])
def test_a_bad_value_at_run_time_is_refused_with_a_reason_and_the_world_goes_on(
        ros, name, value, words):
    world = ros.start_world(paused=True)
    before = world.node.parameters[name]
    result = ros.set_parameter('mujoco', name, value)
    assert not result.successful
    for word in words:
        assert word in result.reason, result.reason
    assert world.node.parameters[name] == before
    assert world.step(100) == pytest.approx(0.2, abs=1e-9)
    assert world.models() == ['tinybot']


def test_publish_rates_set_at_run_time_space_the_messages_out(ros):
    # Not free-running, where every stream is also held to its rate in wall time.
    world = ros.start_world(real_time_factor=4.0)
    odometry = ros.subscribe(Odometry, '/odom')
    assert ros.wait_for(lambda: odometry), 'no odom'
    for name, rate in (('clock_publish_rate', 50), ('odom_publish_rate', 10.0)):
        assert ros.set_parameter('mujoco', name, rate).successful
    # Messages sent before the sets may still be on their way: judge those stamped after.
    set_at = world.node.world.time
    world.wait_sim(1.0)
    clock = [sim for _, sim in list(world.clock) if sim > set_at][1:]
    odom = [stamp for stamp in (seconds_of(msg.header.stamp) for msg in list(odometry))
            if stamp > set_at][1:]
    for stamps, period in ((clock, 0.02), (odom, 0.1)):
        gaps = [later - earlier for earlier, later in zip(stamps, stamps[1:])]
        assert gaps and all(gap == pytest.approx(period, abs=0.0011) for gap in gaps), gaps


def turning_rate(world):
    return world.state('tinybot').twist.angular.z


def test_cmd_vel_timeout_set_at_run_time_applies_to_the_command_in_force(ros):
    world = ros.start_world(paused=True)
    assert ros.set_parameter('mujoco', 'cmd_vel_timeout', 0).successful  # an integer: never lapse
    assert world.node.parameters['cmd_vel_timeout'] == 0.0
    twist = Twist()
    twist.angular.z = 1.0
    world.command('/cmd_vel', twist)
    world.step(250)
    assert turning_rate(world) > 0.5, 'tinybot did not start turning'
    world.step(500)
    assert turning_rate(world) > 0.5, 'the command lapsed although cmd_vel_timeout is 0'
    # The command came over a simulated second ago: a timeout of 0.2 s ends it at once.
    assert ros.set_parameter('mujoco', 'cmd_vel_timeout', 0.2).successful
    world.step(250)
    assert abs(turning_rate(world)) < 0.05, 'tinybot kept turning after its command lapsed'


def test_camera_settings_set_at_run_time_take_effect(ros, tmp_path):
    world = ros.start_world(real_time_factor=0.0)
    topics = {name for name, _ in world.node.get_topic_names_and_types()}
    assert '/mujoco/camera/image_raw' not in topics
    images = ros.subscribe(Image, '/mujoco/camera/image_raw')
    infos = ros.subscribe(CameraInfo, '/mujoco/camera/camera_info')
    for name, value in (('camera_width', 64), ('camera_height', 48), ('camera_rate', 20),
                        ('camera_enabled', True)):
        assert ros.set_parameter('mujoco', name, value).successful, name
    assert ros.wait_for(lambda: images and infos, timeout=20.0), 'no image after enabling'
    assert (images[-1].width, images[-1].height) == (64, 48)

    focal = infos[-1].k[0]
    assert ros.set_parameter('mujoco', 'camera_fovy', 30.0).successful
    assert ros.set_parameter('mujoco', 'camera_width', 80).successful
    assert ros.wait_for(lambda: images[-1].width == 80 and infos[-1].k[0] > 1.5 * focal,
                        timeout=20.0), 'size and field of view did not change'
    count = len(images)
    assert ros.set_parameter('mujoco', 'camera_position', [0.0, -3.0, 1.0]).successful
    assert ros.wait_for(lambda: len(images) > count + 1, timeout=20.0)
    assert world.node.camera_stream.camera.position.tolist() == [0.0, -3.0, 1.0]

    assert ros.set_parameter('mujoco', 'snapshot_directory', str(tmp_path)).successful
    answer = ros.call(Trigger, '/mujoco/save_snapshot', Trigger.Request(), timeout=30.0)
    assert answer.success and os.path.dirname(answer.message) == str(tmp_path), answer.message
    with PillowImage.open(answer.message) as png:
        assert png.size == (80, 48)

    assert ros.set_parameter('mujoco', 'camera_enabled', False).successful
    assert '/mujoco/camera/image_raw' not in world.published_topics()
    assert world.node.camera_stream.next_due == math.inf
