"""The drives in both spellings, with wheel pairs, and the skid steer: parameters and motion."""

import math
import re

import numpy as np
import pytest
from repository import model_path, read_model, TEST_MODELS
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.diff_drive import DiffDrive
from service_tutorial.sim.plugins.diff_drive import MAX_WHEEL_RIM_SPEED
from service_tutorial.sim.plugins.diff_drive import Odometry
from service_tutorial.sim.plugins.drive_config import ODOMETRY_SOURCE_ENCODER
from service_tutorial.sim.plugins.drive_config import ODOMETRY_SOURCE_WORLD
from service_tutorial.sim.plugins.skid_steer import SkidSteer
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.validation import WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_robot
from worlds import drive_and_stop, settled_world

DIFF_DRIVES = ('diffbot_ros1', 'diffbot_ros2', 'pairbot_ros2')
UNMEASURED = 1e12


def settled(name, **world_options):
    """Return a world with a test robot that has settled for half a second."""
    return settled_world(name, model_path(name, TEST_MODELS), **world_options)


@pytest.mark.parametrize('name', DIFF_DRIVES)
@pytest.mark.parametrize('linear_x, angular_z', [(0.5, 0.0), (0.0, 0.5), (0.0, -0.5)])
def test_differential_drives_drive_and_turn_within_three_percent(name, linear_x, angular_z):
    # 1 m at 0.5 m/s, or 1 rad at 0.5 rad/s either way.
    turned, travelled = drive_and_stop(settled(name), name, linear_x, angular_z, 2.0)
    print(f'\n{name}, linear.x {linear_x} angular.z {angular_z} for 2 s: travelled '
          f'{travelled:.4f} m, turned {turned:.4f} rad')
    if linear_x:
        assert travelled == pytest.approx(1.0, rel=0.03)
        assert abs(turned) < 0.03
    else:
        assert turned == pytest.approx(math.copysign(1.0, angular_z), rel=0.03)
        assert travelled < 0.03


def test_skid_steer_drives_straight_and_turns_the_commanded_way():
    _, travelled = drive_and_stop(settled('skidbot_ros1'), 'skidbot_ros1', 0.5, 0.0, 2.0)
    print(f'\nskidbot_ros1, linear.x 0.5 for 2 s: travelled {travelled:.4f} m')
    assert travelled == pytest.approx(1.0, rel=0.03)
    for angular_z in (0.5, -0.5):
        turned, travelled = drive_and_stop(settled('skidbot_ros1'), 'skidbot_ros1', 0.0,
                                           angular_z, 2.0)
        print(f'skidbot_ros1, angular.z {angular_z} for 2 s: turned {turned:.4f} rad')
        # The wheels skid sideways to turn: at least half the commanded 1 rad remains.
        assert 0.5 <= turned * math.copysign(1.0, angular_z) <= 1.03
        assert travelled < 0.03


def test_ros1_spelling():
    config = load_urdf(read_model('diffbot_ros1', TEST_MODELS)).diff_drive
    assert (config.left_joints, config.right_joints) == (('left_hinge',), ('right_hinge',))
    assert (config.wheel_separation, config.wheel_diameter) == (0.22, 0.08)
    # <wheelTorque> is the diff drive's limit; <torque> is the skid steer's, not read here.
    assert config.max_wheel_torque == 1.5 and config.max_wheel_acceleration == 0.0
    assert config.odometry_source == ODOMETRY_SOURCE_WORLD
    assert config.publish_odom and config.publish_odom_tf and config.publish_wheel_joint_state
    assert not config.publish_wheel_tf and config.update_rate == 20.0
    # ROS 1's diff drive reports a fixed pose covariance and no twist covariance.
    assert config.covariance == (1e-5, 1e-5, UNMEASURED, UNMEASURED, UNMEASURED, 1e-3,
                                 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    assert config.notes == ()


def test_ros2_spelling():
    config = load_urdf(read_model('diffbot_ros2', TEST_MODELS)).diff_drive
    assert (config.left_joints, config.right_joints) == (('left_wheel_joint',),
                                                         ('right_wheel_joint',))
    assert (config.max_wheel_torque, config.max_wheel_acceleration) == (2.0, 2.0)
    assert config.odometry_source == ODOMETRY_SOURCE_ENCODER
    assert config.publish_odom and config.publish_odom_tf and not config.publish_wheel_tf
    assert not config.publish_wheel_joint_state and config.update_rate == 50.0
    pose = (2e-4, 2e-4, UNMEASURED, UNMEASURED, UNMEASURED, 2e-3)
    assert config.covariance == pose + pose


def test_ros2_wheel_pairs_each_with_their_separation_and_diameter():
    config = load_urdf(read_model('pairbot_ros2', TEST_MODELS)).diff_drive
    assert config.wheel_pairs() == (
        ('inner_left_joint', 'inner_right_joint', 0.18, 0.08),
        ('outer_left_joint', 'outer_right_joint', 0.38, 0.12))
    # Encoder odometry and the config's single values are the first pair's.
    assert (config.left_joint, config.wheel_separation, config.wheel_radius) == (
        'inner_left_joint', 0.18, 0.04)


def test_each_wheel_pair_turns_at_its_own_speeds():
    world = settled('pairbot_ros2')
    world.models['pairbot_ros2'].drive().command_velocity(0.2, 1.0)
    world.step(200)
    names, _, speeds = world.joint_state('pairbot_ros2')
    speed = dict(zip(names, speeds))
    for side, sign in (('left', -1.0), ('right', 1.0)):
        assert speed[f'inner_{side}_joint'] == pytest.approx((0.2 + sign * 0.09) / 0.04, rel=0.02)
        assert speed[f'outer_{side}_joint'] == pytest.approx((0.2 + sign * 0.19) / 0.06, rel=0.02)


def test_skid_steer_parameters():
    description = load_urdf(read_model('skidbot_ros1', TEST_MODELS))
    (setup,) = description.plugins
    config = setup.config
    assert setup.kind == 'gazebo_ros_skid_steer_drive'
    assert config.wheel_pairs() == (
        ('front_left_wheel_joint', 'front_right_wheel_joint', 0.3, 0.1),
        ('rear_left_wheel_joint', 'rear_right_wheel_joint', 0.3, 0.1))
    assert config.max_wheel_torque == 5.0 and config.max_wheel_acceleration == 0.0
    assert config.odometry_source == ODOMETRY_SOURCE_WORLD
    assert config.publish_odom and config.publish_odom_tf and not config.publish_wheel_joint_state
    pose = (1e-4, 1e-4, UNMEASURED, UNMEASURED, UNMEASURED, 1e-2)
    assert config.covariance == pose + pose and config.update_rate == 100.0


INERTIAL = ('<inertial><mass value="{mass}"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
            'ixy="0" ixz="0" iyz="0"/></inertial>')


def wheeled(plugin, wheels=('left', 'right')):
    """Return a URDF of a chassis with continuous wheel joints and one plugin block."""
    links = [f'<link name="chassis">{INERTIAL.format(mass=1)}</link>']
    for wheel in wheels:
        links.append(f'<link name="{wheel}_wheel">{INERTIAL.format(mass=0.1)}</link>'
                     f'<joint name="{wheel}" type="continuous"><parent link="chassis"/>'
                     f'<child link="{wheel}_wheel"/><axis xyz="0 1 0"/></joint>')
    return f'<robot name="r">{"".join(links)}<gazebo>{plugin}</gazebo></robot>'


def diff_drive(*tags):
    return f'<plugin name="d" filename="libgazebo_ros_diff_drive.so">{"".join(tags)}</plugin>'


ROS1_JOINTS = '<leftJoint>left</leftJoint><rightJoint>right</rightJoint>'
ROS2_JOINTS = '<left_joint>left</left_joint><right_joint>right</right_joint>'


def test_ros1_defaults():
    config = load_urdf(wheeled(diff_drive(ROS1_JOINTS))).diff_drive
    assert (config.wheel_separation, config.wheel_diameter) == (0.34, 0.15)
    assert (config.max_wheel_torque, config.max_wheel_acceleration) == (5.0, 0.0)
    assert config.odometry_source == ODOMETRY_SOURCE_WORLD and config.update_rate == 100.0
    assert config.publish_odom and config.publish_odom_tf
    assert not config.publish_wheel_tf and not config.publish_wheel_joint_state
    assert not config.legacy_mode and config.left_joints == ('left',)
    assert config.notes == ()


def test_ros1_publish_tf_false_means_no_odometry_topic():
    config = load_urdf(wheeled(diff_drive(ROS1_JOINTS, '<publishTf>0</publishTf>'))).diff_drive
    assert not config.publish_odom and config.publish_odom_tf


@pytest.mark.parametrize('tags, note', [
    ('<publishOdomTF>0</publishOdomTF>',
     "diff-drive <publishOdomTF> is '0', which gazebo_ros reads only as true or false; the "
     'default true is kept'),
    ('<odometrySource>0</odometrySource>',
     "diff-drive <odometrySource> '0' is not read by this generation of gazebo_ros, which "
     'keeps its default: world (ground truth)'),
    ('<torque>10</torque>',
     'diff-drive <torque> is not read by gazebo_ros_diff_drive, whose wheel torque limit is '
     '<wheelTorque>; its default 5 N m is used'),
])
def test_ros1_values_gazebo_ros_would_not_take_are_noted(tags, note):
    description = load_urdf(wheeled(diff_drive(ROS1_JOINTS, tags)))
    config = description.diff_drive
    assert config.notes == (note,) and note in description.notes
    assert config.publish_odom_tf and config.odometry_source == ODOMETRY_SOURCE_WORLD
    assert config.max_wheel_torque == 5.0


def test_ros2_values_gazebo_ros_would_not_take_are_noted():
    config = load_urdf(wheeled(diff_drive(
        ROS2_JOINTS, '<odometry_source>encoder</odometry_source>',
        '<wheel_separation>0.3</wheel_separation><wheel_separation>0.5</wheel_separation>'
    ))).diff_drive
    assert config.odometry_source == ODOMETRY_SOURCE_WORLD
    assert config.wheel_separation == 0.3
    assert len(config.notes) == 2


def test_ros2_pairs_without_their_own_values_take_the_defaults():
    config = load_urdf(wheeled(diff_drive(
        '<num_wheel_pairs>2</num_wheel_pairs><left_joint>l1</left_joint>'
        '<right_joint>r1</right_joint><left_joint>l2</left_joint><right_joint>r2</right_joint>'
        '<wheel_separation>0.3</wheel_separation>'), wheels=('l1', 'r1', 'l2', 'r2'))
    ).diff_drive
    assert [pair[2:] for pair in config.wheel_pairs()] == [(0.3, 0.15), (0.34, 0.15)]


@pytest.mark.parametrize('plugin, message', [
    (diff_drive('<num_wheel_pairs>2</num_wheel_pairs>', ROS2_JOINTS),
     'names 1 <left_joint> and 1 <right_joint>, but <num_wheel_pairs> is 2'),
    (diff_drive('<left_joint>left</left_joint><right_joint>left</right_joint>'),
     'names the same wheel joint twice'),
    (diff_drive(ROS2_JOINTS, '<odometry_source>gps</odometry_source>'),
     "<odometry_source> must be '0' or '1': 'gps'"),
    (diff_drive(ROS1_JOINTS, '<odometrySource>gps</odometrySource>'),
     "<odometrySource> must be 'encoder' or 'world': 'gps'"),
    (diff_drive(ROS1_JOINTS, '<wheelTorque>-1</wheelTorque>'),
     "diff-drive <wheelTorque> must be one number > 0: '-1'"),
    (diff_drive(ROS1_JOINTS, '<robotBaseFrame>//a//b//</robotBaseFrame>'),
     "diff-drive <robotBaseFrame> '//a//b//' is not a valid frame id: it has an empty part "
     "(a doubled, leading or trailing '/')"),
    (diff_drive(ROS2_JOINTS, '<odometry_frame>odom/</odometry_frame>'),
     "diff-drive <odometry_frame> 'odom/' is not a valid frame id: it has an empty part "
     "(a doubled, leading or trailing '/')"),
    (diff_drive(ROS2_JOINTS, '<robot_base_frame>base\tlink</robot_base_frame>'),
     "diff-drive <robot_base_frame> 'base\\tlink' is not a valid frame id: it holds "
     'whitespace or control characters'),
    (diff_drive(ROS2_JOINTS, '<update_rate>1e308</update_rate>'),
     'diff-drive <update_rate> must be at most 10000 Hz: 1e+308'),
    (diff_drive(ROS1_JOINTS, '<updateRate>-1</updateRate>'),
     "diff-drive <updateRate> must be one number >= 0: '-1'"),
    (diff_drive(ROS1_JOINTS, '<updateRate>inf</updateRate>'),
     "diff-drive <updateRate> contains NaN or infinity: 'inf'"),
    (diff_drive(ROS2_JOINTS, '<wheel_separation>2e3</wheel_separation>'),
     'diff-drive <wheel_separation> must be at most 1000 m: 2000'),
    (diff_drive(ROS1_JOINTS, '<wheelDiameter>1e20</wheelDiameter>'),
     'diff-drive <wheelDiameter> must be at most 1000 m: 1e+20'),
    (diff_drive(ROS2_JOINTS, '<publish_odom>maybe</publish_odom>'),
     "diff-drive <publish_odom> must be true or false: 'maybe'"),
    (diff_drive(ROS2_JOINTS, '<covariance_x>nan</covariance_x>'),
     "diff-drive <covariance_x> contains NaN or infinity: 'nan'"),
    (diff_drive('<leftJoint>left</leftJoint>'),
     "diff-drive wheel joint 'right_joint' is not a joint of the robot"),
    ('<plugin name="s" filename="libgazebo_ros_skid_steer_drive.so"/>',
     "skid-steer wheel joint 'left_front_joint' is not a joint of the robot"),
    (diff_drive(ROS2_JOINTS) + '<plugin name="s" filename="libgazebo_ros_skid_steer_drive.so">'
     '<leftFrontJoint>left</leftFrontJoint></plugin>',
     'carries a skid-steer plugin besides another drive'),
])
def test_drive_blocks_that_are_refused(plugin, message):
    with pytest.raises(UrdfError, match=re.escape(message)):
        load_urdf(wheeled(plugin))


def test_a_ros1_leading_slash_is_dropped_from_the_drives_frames():
    config = load_urdf(wheeled(diff_drive(
        ROS1_JOINTS, '<odometryFrame>/odom</odometryFrame>',
        '<robotBaseFrame>/base_footprint</robotBaseFrame>'))).diff_drive
    assert (config.odometry_frame, config.robot_base_frame) == ('odom', 'base_footprint')


def test_driven_joints_lose_their_friction_and_keep_damping_and_the_torque_limit():
    world = settled('diffbot_ros1')
    model, mj_model = world.models['diffbot_ros1'], world.model
    for joint in ('left_hinge', 'right_hinge'):
        dof = mj_model.jnt_dofadr[mj_model.joint(model.scoped(joint)).id]
        assert mj_model.dof_frictionloss[dof] == 0.0
        assert mj_model.dof_damping[dof] == pytest.approx(0.01)
    np.testing.assert_allclose(mj_model.actuator_forcerange[model.actuator_index],
                               [[-1.5, 1.5]] * 2)


def test_the_wheels_never_push_harder_than_the_torque_limit():
    urdf = read_model('diffbot_ros2', TEST_MODELS).replace(
        '<max_wheel_torque>2</max_wheel_torque>', '<max_wheel_torque>0.05</max_wheel_torque>')
    world = World()
    spawn_robot(world, 'weak', urdf)
    world.step(250)
    forces = []
    for _ in range(100):
        world.models['weak'].drive().command_velocity(0.5, 0.0)
        world.step(5)
        forces.append(world.data.actuator_force.copy())
    assert np.abs(forces).max() == pytest.approx(0.05)
    # 0.05 N m on each 5 cm wheel pushes 2.4 kg at about 0.8 m/s^2: 0.4 m/s after 0.5 s.
    assert world.get_model_state('weak').linear_velocity[0] < 0.45


def test_the_wheels_speed_up_at_the_acceleration_limit():
    world = settled('diffbot_ros2')
    radius = 0.05
    rims = []
    for _ in range(20):
        world.models['diffbot_ros2'].drive().command_velocity(0.5, 0.0)
        world.step(10)
        rims.append(world.joint_state('diffbot_ros2')[2] * radius)
    rims = np.array(rims)
    # 2 m/s^2 at the rim: 0.04 m/s more every 20 ms until 0.5 m/s, reached after 0.25 s.
    np.testing.assert_allclose(np.diff(rims[:10], axis=0), 0.04, atol=0.002)
    np.testing.assert_allclose(rims[15:], 0.5, atol=0.01)


def test_every_drive_offers_the_interface_of_the_ros_face():
    for name, kind in (('diffbot_ros2', DiffDrive), ('skidbot_ros1', SkidSteer)):
        world = settled(name, cmd_vel_timeout=0.0)
        drive = world.models[name].drive()
        assert type(drive) is kind and drive.is_drive
        assert [other for other, model in world.models.items() if model.drive()] == [name]
        assert drive.command_velocity(0.3, 0.2) == (0.3, 0.2)
        world.step(500)
        odometry = drive.odometry()
        assert isinstance(odometry, Odometry)
        assert odometry.linear_velocity[0] == pytest.approx(0.3, rel=0.05)
        assert (odometry.odometry_frame, odometry.robot_base_frame) == ('odom',
                                                                        'base_footprint')
        config = drive.config
        assert (config.odometry_frame, config.robot_base_frame) == ('odom', 'base_footprint')
        assert isinstance(config.publish_odom, bool) and isinstance(config.publish_odom_tf, bool)
        assert isinstance(config.publish_wheel_joint_state, bool)
        assert config.update_rate > 0.0 and len(config.covariance) == 12


def test_a_command_too_fast_for_a_wheel_pair_is_scaled_down_by_the_fastest_rim():
    world = settled('pairbot_ros2')
    drive = world.models['pairbot_ros2'].drive()
    # The outer pair, 0.38 m apart, turns its rims fastest: 100 rad/s * 0.19 m = 19 m/s.
    linear_x, angular_z = drive.command_velocity(0.0, 100.0)
    assert linear_x == 0.0
    assert angular_z * 0.19 == pytest.approx(MAX_WHEEL_RIM_SPEED)
    with pytest.raises(WorldError, match='angular_z is NaN or infinite'):
        drive.command_velocity(0.0, math.nan)
