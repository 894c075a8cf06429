"""
gz-sim's systems, simulated: DiffDrive, JointStatePublisher, OdometryPublisher, joint controllers.

The suite's own robots with gz-sim blocks (test/models/sdf/models/surveyor, an SDF model, and
test/models/gzbot.urdf, a URDF) are spawned into a ROS-free World and driven through their
plugins, in simulation time: a command is held with no timeout and its speed ramps at the
acceleration limit, wheel odometry follows ground truth, the systems' topics and frames take
gz's names. Bad parameters are refused naming what is wrong, and the robots spawned before
keep running.
"""

import math
import os

import numpy as np
import pytest
from repository import TEST_MODELS
from service_tutorial.sim.plugins.gz_diff_drive import GzDiffDrive
from service_tutorial.sim.plugins.speed_limits import SpeedLimits
from service_tutorial.sim.validation import WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

SURVEYOR = os.path.join(TEST_MODELS, 'sdf', 'models', 'surveyor', 'model.sdf')
GZBOT = os.path.join(TEST_MODELS, 'gzbot.urdf')
TIMESTEP = 0.001


def steps(seconds):
    return round(seconds / TIMESTEP)


@pytest.fixture
def world():
    return World(timestep=TIMESTEP, cmd_vel_timeout=0.5)


def settled(world, name, path, **placement):
    """Spawn a robot from a file and let it come to rest on its wheels for 0.5 s."""
    model = spawn_file(world, name, path, **placement)
    world.step(steps(0.5))
    return model


def ramped_distance(speed, acceleration, seconds):
    """Return how far a speed reached at a constant acceleration takes a robot in seconds."""
    ramp = speed / acceleration
    return speed * seconds - speed * ramp / 2.0


@pytest.mark.parametrize('path, name, acceleration', [(SURVEYOR, 'surveyor', 5.0),
                                                      (GZBOT, 'gzbot', 4.0)])
def test_a_robot_drives_at_its_command_within_its_acceleration_ramp(world, path, name,
                                                                    acceleration):
    robot = settled(world, name, path)
    drive = robot.drive()
    assert isinstance(drive, GzDiffDrive)
    start = world.get_model_state(name).position
    drive.command_velocity(0.2, 0.0)
    world.step(steps(1.0))
    end = world.get_model_state(name).position
    travelled = end[0] - start[0]
    print(f'\n{name}: 0.2 m/s for 1 s travelled {travelled:.4f} m')
    assert 0.19 <= travelled <= 0.21
    assert travelled == pytest.approx(ramped_distance(0.2, acceleration, 1.0), abs=0.005)
    assert abs(end[1] - start[1]) < 0.005
    # Wheel odometry from spawn, where the robot settled a little after its start.
    odometry = drive.odometry()
    assert odometry.position[0] == pytest.approx(end[0], abs=0.005)
    assert odometry.linear_velocity[0] == pytest.approx(0.2, abs=0.005)


def test_the_ramp_climbs_at_the_acceleration_limit(world):
    robot = settled(world, 'surveyor', SURVEYOR)
    drive = robot.drive()
    drive.command_velocity(0.2, 0.0)
    world.step(steps(0.02))  # halfway up the ramp at 5 m/s^2
    assert drive.speeds[0] == pytest.approx(0.1, abs=0.006)
    world.step(steps(0.03))
    assert drive.speeds == (0.2, 0.0)
    # Stopping ramps down at min_linear_acceleration: -5 m/s^2.
    drive.command_velocity(0.0, 0.0)
    world.step(steps(0.02))
    assert drive.speeds[0] == pytest.approx(0.1, abs=0.006)


def test_the_last_command_is_held_with_no_timeout(world):
    robot = settled(world, 'gzbot', GZBOT)
    robot.drive().command_velocity(0.1, 0.5)
    world.step(steps(3.0))  # six times the world's cmd_vel_timeout
    state = world.get_model_state('gzbot')
    assert np.linalg.norm(state.linear_velocity[:2]) == pytest.approx(0.1, abs=0.01)
    assert state.angular_velocity[2] == pytest.approx(0.5, abs=0.02)


def test_a_disabled_drive_stops_and_takes_no_command(world):
    drive = settled(world, 'surveyor', SURVEYOR).drive()
    drive.command_velocity(0.2, 0.0)
    world.step(steps(0.5))
    drive.set_enabled(False)
    drive.command_velocity(0.3, 0.0)
    world.step(steps(0.5))
    assert drive.target == (0.0, 0.0)
    assert abs(world.get_model_state('surveyor').linear_velocity[0]) < 0.005


def test_odometry_and_its_frames_take_gz_names_or_the_blocks(world):
    surveyor = settled(world, 'surveyor', SURVEYOR)
    gzbot = settled(world, 'gzbot', GZBOT, position=(0.0, 1.0, 0.0))
    drive = surveyor.drive()
    assert drive.gz_topics('surveyor') == {
        'cmd_vel': '/model/surveyor/cmd_vel', 'enable': '/model/surveyor/enable',
        'odometry': '/model/surveyor/odometry', 'tf': '/tf'}
    assert (drive.odometry_frame, drive.base_frame) == ('odom', 'chassis')
    assert gzbot.drive().gz_topics('gzbot') == {
        'cmd_vel': '/cmd_vel', 'enable': '/model/gzbot/enable', 'odometry': '/odom',
        'tf': '/tf'}
    # Odometry starts where the robot was spawned, whatever its pose in the world.
    odometry = gzbot.drive().odometry()
    assert np.abs(odometry.position).max() < 1e-3
    # A robot spawned from the same file under another name: gz's names follow its name.
    plain = spawn_robot(world, 'plain', SDF_DRIVE.format(extra=''), model_format='sdf',
                        position=(0.0, -1.0, 0.0))
    assert plain.drive().gz_topics('plain')['odometry'] == '/model/plain/odometry'
    assert (plain.drive().odometry_frame, plain.drive().base_frame) == ('plain/odom',
                                                                        'plain/body')


def test_odometry_goes_to_its_listener_at_its_frequency(world):
    surveyor = settled(world, 'surveyor', SURVEYOR)
    gzbot = settled(world, 'gzbot', GZBOT, position=(0.0, 1.0, 0.0))
    heard = {'surveyor': [], 'gzbot': []}
    for robot in (surveyor, gzbot):
        robot.drive().listener = lambda drive, name=robot.name: heard[name].append(world.time)
    world.step(steps(1.0))
    assert len(heard['surveyor']) == 50 and len(heard['gzbot']) == 30
    assert np.diff(heard['gzbot']) == pytest.approx(np.full(29, 1 / 30), abs=TIMESTEP)


def test_jerk_limits_shape_the_speed_step_by_step_as_gz_math_does(world):
    text = SDF_DRIVE.format(extra='<max_linear_jerk>100</max_linear_jerk>'
                            '<min_linear_jerk>-100</min_linear_jerk>'
                            '<max_linear_acceleration>2</max_linear_acceleration>')
    drive = spawn_robot(world, 'jerky', text, model_format='sdf').drive()
    world.step(steps(0.2))
    drive.command_velocity(0.3, 0.0)
    expected, history = [], (0.0, 0.0)
    limits = SpeedLimits(min_jerk=-100.0, max_jerk=100.0, max_acceleration=2.0)
    for _ in range(200):
        speed = limits.limit(0.3, *history, TIMESTEP)
        history = (speed, history[0])
        expected.append(speed)
    seen = [drive.speeds[0]]
    for _ in range(199):
        world.step(1)
        seen.append(drive.speeds[0])
    assert seen == pytest.approx(expected, abs=1e-12)
    # The acceleration grows by the jerk limit, then holds at 2 m/s^2.
    assert seen[10] - seen[9] == pytest.approx(11 * 100 * TIMESTEP ** 2, rel=1e-6)
    assert seen[150] - seen[149] == pytest.approx(2.0 * TIMESTEP, rel=1e-6)


def test_speed_limits_clamp_jerk_then_acceleration_then_speed():
    limits = SpeedLimits(min_velocity=-0.5, max_velocity=0.5, min_acceleration=-1.0,
                         max_acceleration=1.0, min_jerk=-10.0, max_jerk=10.0)
    # From rest, a jump to 1 m/s: the acceleration may grow by 10 m/s^3 * 0.1 s = 1 m/s^2.
    assert limits.limit(1.0, 0.0, 0.0, 0.1) == pytest.approx(0.1)
    # Already accelerating at 0.5 m/s^2: up to 1.5 by jerk, then 1 by acceleration.
    assert limits.limit(1.0, 0.45, 0.4, 0.1) == pytest.approx(0.55 - 0.05)
    assert limits.limit(5.0, 0.5, 0.5, 10.0) == 0.5
    ramp = SpeedLimits(max_acceleration=2.0).ramp(0.0, 0.3, 1.0, 0.01)
    assert (ramp.rate, ramp.end) == (2.0, pytest.approx(1.0 + 15 * 0.01))
    # Without a limit on slowing down, a stop is at once, as in gz.
    assert SpeedLimits(max_acceleration=2.0).ramp(0.3, 0.0, 1.0, 0.01).end == 1.0


def test_joint_states_name_the_listed_joints_with_their_forces(world):
    surveyor = settled(world, 'surveyor', SURVEYOR)
    gzbot = settled(world, 'gzbot', GZBOT, position=(0.0, 1.0, 0.0))
    surveyor.drive().command_velocity(0.2, 0.0)
    world.step(steps(0.5))
    publisher = surveyor.plugins[1]
    assert publisher.gz_topics('surveyor', 'default') == {
        'joint_state': '/world/default/model/surveyor/joint_state'}
    names, positions, velocities = publisher.joint_state()
    assert names == ['left_wheel_joint', 'right_wheel_joint']
    assert velocities == pytest.approx([4.0, 4.0], abs=0.05)  # 0.2 m/s on 0.05 m wheels
    assert positions[0] > 1.5
    assert np.abs(publisher.joint_efforts()).max() > 0.0
    assert gzbot.plugins[1].gz_topics('gzbot', 'default') == {'joint_state': '/joint_states'}


def test_ground_truth_odometry_is_the_models_pose_in_the_world(world):
    text = SDF_DRIVE.format(extra='').replace(
        '</model>', '<plugin filename="gz-sim-odometry-publisher-system" '
        'name="gz::sim::systems::OdometryPublisher"><odom_publish_frequency>20'
        '</odom_publish_frequency><xyz_offset>0.1 0 0</xyz_offset></plugin></model>')
    robot = spawn_robot(world, 'truth', text, model_format='sdf', position=(1.0, 2.0, 0.0))
    publisher = robot.plugins[1]
    heard = []
    publisher.listener = lambda plugin: heard.append(plugin.odometry())
    world.step(steps(0.5))
    assert len(heard) == 10
    odometry = heard[-1]
    assert odometry.position == pytest.approx([1.1, 2.0, 0.0], abs=2e-3)
    assert (odometry.odometry_frame, odometry.robot_base_frame) == ('truth/odom',
                                                                    'truth/base_footprint')
    assert publisher.gz_topics('truth') == {
        'odometry': '/model/truth/odometry',
        'odometry_with_covariance': '/model/truth/odometry_with_covariance',
        'tf': '/model/truth/pose'}


ARM = """<sdf version="1.9"><model name="arm">
  <link name="base"><collision name="c"><geometry><box><size>0.2 0.2 0.1</size></box>
    </geometry></collision></link>
  <joint name="anchor" type="fixed"><parent>world</parent><child>base</child></joint>
  <link name="arm"><pose>0 0 0.3 0 0 0</pose>
    <inertial><pose>0 0 0.1 0 0 0</pose><mass>0.5</mass><inertia><ixx>0.002</ixx>
    <iyy>0.002</iyy><izz>0.0002</izz></inertia></inertial>
    <collision name="c"><pose>0 0 0.1 0 0 0</pose><geometry><box><size>0.02 0.02 0.2</size>
    </box></geometry></collision></link>
  <joint name="shoulder" type="revolute"><parent>base</parent><child>arm</child>
    <axis><xyz>1 0 0</xyz><limit><lower>-2</lower><upper>2</upper></limit></axis></joint>
  {plugin}
</model></sdf>"""


def test_a_joint_position_controller_holds_its_joint_at_the_target(world):
    plugin = ('<plugin filename="gz-sim-joint-position-controller-system" '
              'name="gz::sim::systems::JointPositionController"><joint_name>shoulder'
              '</joint_name><p_gain>20</p_gain><d_gain>1</d_gain><i_gain>5</i_gain>'
              '<initial_position>0.3</initial_position></plugin>')
    arm = spawn_robot(world, 'arm', ARM.format(plugin=plugin), model_format='sdf')
    controller = arm.plugins[0]
    assert controller.gz_topics('arm') == {'command': '/model/arm/joint/shoulder/0/cmd_pos'}
    world.step(steps(2.0))
    shoulder = world.joint_state('arm')[1][0]
    assert shoulder == pytest.approx(0.3, abs=0.02)  # the initial position is the target
    controller.command(-0.5)
    world.step(steps(3.0))
    assert world.joint_state('arm')[1][0] == pytest.approx(-0.5, abs=0.02)


def test_a_joint_controller_turns_its_joint_at_the_commanded_speed(world):
    plugin = ('<plugin filename="gz-sim-joint-controller-system" '
              'name="gz::sim::systems::JointController"><joint_name>shoulder</joint_name>'
              '<topic>spin</topic></plugin>')
    arm = spawn_robot(world, 'arm', ARM.format(plugin=plugin).replace(
        '<limit><lower>-2</lower><upper>2</upper></limit>', ''), model_format='sdf')
    controller = arm.plugins[0]
    assert controller.gz_topics('arm') == {'command': '/spin'}
    controller.command(1.5)
    world.step(steps(0.5))
    assert world.joint_state('arm')[2][0] == pytest.approx(1.5, abs=0.01)
    with pytest.raises(WorldError, match='command is NaN'):
        controller.command(math.nan)


SDF_DRIVE = """<sdf version="1.9"><model name="plain">
  <link name="body"><pose>0 0 0.06 0 0 0</pose>
    <inertial><pose>0.03 0 0 0 0 0</pose><mass>2</mass><inertia><ixx>0.01</ixx>
    <iyy>0.01</iyy><izz>0.01</izz></inertia></inertial>
    <collision name="c"><geometry><box><size>0.2 0.16 0.06</size></box></geometry>
    </collision>
    <collision name="caster"><pose>0.08 0 -0.045 0 0 0</pose><geometry><sphere>
    <radius>0.015</radius></sphere></geometry><surface><friction><ode><mu>0</mu><mu2>0</mu2>
    </ode></friction></surface></collision></link>
  <link name="left"><pose>0 0.1 0.03 -1.5708 0 0</pose>
    <collision name="c"><geometry><cylinder><radius>0.03</radius><length>0.02</length>
    </cylinder></geometry></collision></link>
  <link name="right"><pose>0 -0.1 0.03 -1.5708 0 0</pose>
    <collision name="c"><geometry><cylinder><radius>0.03</radius><length>0.02</length>
    </cylinder></geometry></collision></link>
  <joint name="left_joint" type="continuous"><parent>body</parent><child>left</child>
    <axis><xyz>0 0 1</xyz></axis></joint>
  <joint name="right_joint" type="continuous"><parent>body</parent><child>right</child>
    <axis><xyz>0 0 1</xyz></axis></joint>
  <plugin filename="gz-sim-diff-drive-system" name="gz::sim::systems::DiffDrive">
    <left_joint>left_joint</left_joint><right_joint>right_joint</right_joint>
    <wheel_separation>0.2</wheel_separation><wheel_radius>0.03</wheel_radius>{extra}
  </plugin>
</model></sdf>"""


@pytest.mark.parametrize('extra, words', [
    ('<wheel_radius>-0.1</wheel_radius>', 'DiffDrive <wheel_radius> must be above 0 and at '
     "most 1000: '-0.1'"),
    ('<wheel_separation>nan</wheel_separation>', 'DiffDrive <wheel_separation> contains NaN'),
    ('<wheel_radius>1e9</wheel_radius>', 'DiffDrive <wheel_radius> must be above 0 and at '
     'most 1000'),
    ('<left_joint>front_left</left_joint>', "DiffDrive <left_joint> 'front_left' is not a "
     'joint of the robot'),
    ('<right_joint>left_joint</right_joint>', "names joint 'left_joint' as both a left and a "
     'right wheel'),
    ('<min_linear_acceleration>1</min_linear_acceleration>',
     "DiffDrive <min_linear_acceleration> must be at most 0: '1'"),
    ('<max_jerk>-inf</max_jerk>', 'DiffDrive <max_jerk> contains NaN or infinity'),
    ('<odom_publish_frequency>1e9</odom_publish_frequency>',
     "DiffDrive <odom_publish_frequency> must be at most 10000: '1e9'"),
    ('<frame_id>a//b</frame_id>', "DiffDrive <frame_id> 'a//b' is not a valid frame id"),
])
def test_absurd_drive_parameters_are_refused_and_the_others_run_on(world, extra, words):
    good = settled(world, 'surveyor', SURVEYOR)
    good.drive().command_velocity(0.2, 0.0)
    with pytest.raises(WorldError) as refused:
        spawn_robot(world, 'bad', SDF_DRIVE.format(extra=extra), model_format='sdf',
                    position=(0.0, 1.0, 0.0))
    assert words in str(refused.value)
    assert "model 'plain'" in str(refused.value)
    assert world.model_names() == ['surveyor']
    start = world.get_model_state('surveyor').position[0]
    world.step(steps(0.5))
    assert world.get_model_state('surveyor').position[0] - start == pytest.approx(0.1,
                                                                                  abs=0.005)


def test_a_topic_gz_cannot_take_gives_way_to_the_default_and_is_named(world):
    robot = spawn_robot(world, 'plain', SDF_DRIVE.format(
        extra='<topic>@~</topic><odom_publisher_frequency>10</odom_publisher_frequency>'),
        model_format='sdf')
    assert robot.drive().gz_topics('plain')['cmd_vel'] == '/model/plain/cmd_vel'
    assert robot.description.notes == (
        "DiffDrive <odom_publisher_frequency> is no parameter of gz-sim's DiffDrive; it is "
        'ignored, as gz-sim ignores it',
        "DiffDrive <topic> '@~' is no valid gz topic; the system's default is used, as "
        'gz-sim does')


@pytest.mark.parametrize('plugin, words', [
    ('<plugin filename="gz-sim-joint-position-controller-system" name="p"/>',
     'JointPositionController names no <joint_name>'),
    ('<plugin filename="gz-sim-joint-controller-system" name="c"><joint_name>anchor'
     '</joint_name></plugin>', "JointController <joint_name> 'anchor' is a fixed joint"),
    ('<plugin filename="gz-sim-joint-position-controller-system" name="p"><joint_name>shoulder'
     '</joint_name><cmd_min>5</cmd_min><cmd_max>1</cmd_max></plugin>',
     'JointPositionController <cmd_min> 5 is above its <cmd_max> 1'),
    ('<plugin filename="gz-sim-odometry-publisher-system" name="o"><gaussian_noise>nan'
     '</gaussian_noise></plugin>', 'OdometryPublisher <gaussian_noise> contains NaN'),
    ('<plugin filename="gz-sim-odometry-publisher-system" name="o"><dimensions>4</dimensions>'
     '</plugin>', 'OdometryPublisher <dimensions> must be at least 2 and at most 3'),
    ('<plugin filename="gz-sim-joint-state-publisher-system" name="j"><joint_name>elbow'
     '</joint_name></plugin>', "JointStatePublisher <joint_name> 'elbow' is not a joint"),
])
def test_absurd_parameters_of_the_other_systems_are_refused(world, plugin, words):
    with pytest.raises(WorldError, match=words):
        spawn_robot(world, 'arm', ARM.format(plugin=plugin), model_format='sdf')
