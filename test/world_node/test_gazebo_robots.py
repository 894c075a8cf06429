"""
Robots written for Gazebo, brought to the world node through ROS as their users bring them.

The lesson's own files (../shared/lesson/robots beside the repository) are used where they are
found and never copied here; the project's test models in test/models/ cover the same features.
The world is paused and stepped: a drive is measured in simulated time, from a known step.
"""

import math
import os
import types

from file_opens import FileOpens
from geometry_msgs.msg import Twist
import mujoco
from nav_msgs.msg import Odometry
import numpy as np
from programs import run_program
import pytest
from rcl_interfaces.msg import Log
from repository import LESSON_ROBOTS, read_model, TEST_MODELS
from running_world import COMMAND_STEPS, lesson_pose
from sensor_msgs.msg import JointState
from service_tutorial.conversions import make_pose, seconds_of as seconds, yaw_of
from service_tutorial.lesson.spawn_model_client import split_xacro_arguments
from service_tutorial.world_node.node import left_out_of

pytestmark = pytest.mark.ros

LESSON_R2D2 = os.path.join(LESSON_ROBOTS, 'service_tutorial', 'models', 'r2d2.urdf')
LESSON_GCAMP = os.path.join(LESSON_ROBOTS, 'gcamp_gazebo')
needs_lesson = pytest.mark.skipif(
    not os.path.isdir(LESSON_ROBOTS), reason=f'the lesson robots are not at {LESSON_ROBOTS}')


def spawn_client(*args):
    """Run the installed spawn_model_client; return the finished process."""
    return run_program('spawn_model_client', *args)


def tilt_of(orientation):
    """Return the angle between a body's z axis and the world's, in radians."""
    q = orientation
    return math.acos(max(-1.0, min(1.0, 1.0 - 2.0 * (q.x * q.x + q.y * q.y))))


def twist(linear_x=0.0, angular_z=0.0):
    msg = Twist()
    msg.linear.x, msg.angular.z = float(linear_x), float(angular_z)
    return msg


def body_geoms(world, body):
    """Return the ids of the geoms of a body of the world node's compiled model."""
    model = world.node.world.model
    body_id = model.body(body).id
    return [geom for geom in range(model.ngeom) if model.geom_bodyid[geom] == body_id]


def wheel_spacing(world, left_body, right_body):
    """Return the distance between two wheel bodies' origins in the compiled model, in m."""
    data = world.node.world.data
    return float(np.linalg.norm(data.body(left_body).xpos - data.body(right_body).xpos))


def settle(world, name):
    """Step a paused world until a model has come to rest; return its state."""
    for _ in range(20):
        world.step(125)  # 0.25 s
        state = world.state(name)
        speeds = (state.twist.linear.x, state.twist.linear.y, state.twist.linear.z,
                  state.twist.angular.x, state.twist.angular.y, state.twist.angular.z)
        if max(abs(speed) for speed in speeds) < 0.005:
            return state
    pytest.fail(f'{name} did not come to rest: {state.twist}')


def test_the_answer_says_which_meshes_and_plugins_were_left_out():
    def description(meshes=(), plugins=()):
        return types.SimpleNamespace(missing_meshes=meshes, ignored_plugins=plugins)
    assert left_out_of(description()) == ''
    assert left_out_of(description(('l_finger.stl', 'l_finger_tip.stl'))) == (
        '2 meshes not found, left out: l_finger.stl, l_finger_tip.stl')
    assert left_out_of(description(('a.dae',), ('libgazebo_ros_camera.so',))) == (
        '1 mesh not found, left out: a.dae; plugins not simulated: libgazebo_ros_camera.so')
    assert left_out_of(description(plugins=('libgazebo_ros_camera.so',
                                            'libgazebo_ros_laser.so'))) == (
        'plugins not simulated: libgazebo_ros_camera.so, libgazebo_ros_laser.so')


@needs_lesson
def test_the_lessons_r2d2_spawns_unchanged_and_stands_upright(paused_world):
    with open(LESSON_R2D2) as urdf_file:
        urdf = urdf_file.read()
    response = paused_world.spawn('r2d2', urdf, lesson_pose())  # as text: no base directory

    assert response.success, response.status_message
    assert response.status_message == (
        "SpawnModel: Successfully spawned entity 'r2d2' "
        '(2 meshes not found, left out: l_finger.stl, l_finger_tip.stl)')
    paused_world.step(1500)  # 3 s
    state = paused_world.state('r2d2')
    tilt = math.degrees(tilt_of(state.pose.orientation))
    print(f'\nlesson r2d2 after 3 s: x {state.pose.position.x:.4f}, y {state.pose.position.y:.4f}'
          f', z {state.pose.position.z:.4f}, tilt {tilt:.3f} deg')
    assert tilt < 5.0
    assert state.pose.position.x == pytest.approx(-2.0, abs=0.03)
    assert state.pose.position.y == pytest.approx(1.0, abs=0.03)


@pytest.fixture
def gcamp_installed(tmp_path, monkeypatch):
    """Install the lesson's gcamp_gazebo as an ament package in a prefix of its own."""
    if not os.path.isdir(LESSON_GCAMP):
        pytest.skip(f'the lesson robots are not at {LESSON_ROBOTS}')
    prefix = tmp_path / 'prefix'
    markers = prefix / 'share' / 'ament_index' / 'resource_index' / 'packages'
    markers.mkdir(parents=True)
    (markers / 'gcamp_gazebo').touch()
    (prefix / 'share' / 'gcamp_gazebo').symlink_to(os.path.realpath(LESSON_GCAMP))
    # Read at call time by the world node here and by the client it starts.
    monkeypatch.setenv('AMENT_PREFIX_PATH',
                       f'{prefix}{os.pathsep}{os.environ.get("AMENT_PREFIX_PATH", "")}')
    return os.path.join(LESSON_GCAMP, 'urdf', 'tinybot_diff.xacro')


def turn_for(world, name, topic, angular_z, duration):
    """
    Command a turn on topic for duration s of simulated time from the step the command came at.

    Return the yaw change when duration has passed, ground truth from get_model_state, with the
    command still in force (taken again every COMMAND_STEPS steps). Then stop the robot and step
    until it is at rest.
    """
    drive = world.node.world.models[name].drive()
    start_yaw = yaw_of(world.state(name).pose.orientation)
    assert drive.commanded_at is None, 'a command was still in force'
    turned = 0.0  # unwrapped
    steps = world.steps(duration)
    for start in range(0, steps, COMMAND_STEPS):
        world.command(topic, twist(angular_z=angular_z))
        world.step(min(COMMAND_STEPS, steps - start))
        state = world.state(name)
        assert drive.commanded_at is not None, \
            f'the command lapsed before {seconds(state.header.stamp):.3f} s'
        turned += math.remainder(yaw_of(state.pose.orientation) - start_yaw - turned,
                                 2.0 * math.pi)
    world.command(topic, Twist())
    settle(world, name)
    return turned


def test_the_lessons_tinybot_xacro_spawns_through_the_client_and_turns(
        gcamp_installed, paused_world, ros):
    odometry = ros.subscribe(Odometry, '/tb2/odom')
    spawned = spawn_client('--file', gcamp_installed, '--name', 'tb2', '--namespace', 'tb2',
                           '-x', '2')

    assert spawned.returncode == 0, spawned.stdout + spawned.stderr
    assert spawned.stdout.startswith(
        "success: True\nstatus_message: \"SpawnModel: Successfully spawned entity 'tb2'")
    assert 'not found' not in spawned.stdout, 'the DAE mesh was left out'
    model = paused_world.node.world.model
    hokuyo_meshes = [geom for geom in body_geoms(paused_world, 'tb2::hokuyo')
                     if model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_MESH]
    assert hokuyo_meshes and all(model.mesh_vertnum[model.geom_dataid[geom]] > 0
                                 for geom in hokuyo_meshes)

    settle(paused_world, 'tb2')
    turned = turn_for(paused_world, 'tb2', '/tb2/cmd_vel', 0.5, 2.0)
    # The block's wheelSeparation (0.4 m) is not the spacing of the robot's wheel joints
    # (0.3 m). gazebo_ros_diff_drive sets the wheel speeds from wheelSeparation alone, so wheels
    # that grip turn this robot 0.4 / 0.3 times the commanded angle; slip can only take from it.
    gripping = 1.0 * (paused_world.node.world.models['tb2'].drive().config.wheel_separation
                      / wheel_spacing(paused_world, 'tb2::left_wheel', 'tb2::right_wheel'))
    print(f'\nlesson tinybot_diff.xacro, angular.z 0.5 on /tb2/cmd_vel for 2 s after settling: '
          f'turned {turned:.4f} rad ({100.0 * (turned - 1.0):+.1f} %, ground truth); '
          f'wheels that grip would turn it {gripping:.4f} rad')
    assert gripping == pytest.approx(4.0 / 3.0)
    assert 1.0 <= turned <= gripping
    assert odometry, 'nothing on /tb2/odom'


def test_plugin_namespaces_and_remaps_put_the_topics_where_gazebo_would(paused_world, ros):
    world = paused_world
    ros2_drive = read_model('ros_namespaced_drive', TEST_MODELS)
    quiet = ros2_drive.replace('<publish_odom>true</publish_odom>', '')
    ros1_drive = read_model('ros_ros1_namespaced_drive', TEST_MODELS)
    for name, xml, (x, y), namespace in [
            ('bot', ros2_drive, (2.0, 0.0), ''),
            ('fleet_bot', ros2_drive, (2.0, 2.0), 'fleet/one'),
            ('r1', ros1_drive, (-2.0, -1.0), ''),
            ('quiet', quiet, (-2.0, 2.0), 'quiet'),
            ('skid', read_model('skidbot_ros1', TEST_MODELS), (0.0, -3.0), '')]:
        world.spawn_or_fail(name, xml, make_pose(x, y, 0.05), namespace=namespace)
    world.step(world.steps(0.5))  # they land and come to rest

    topics = world.topics()
    assert {'/bot/cmd', '/bot/odometry/wheels', '/fleet/one/cmd', '/fleet/one/odometry/wheels',
            '/r1/drive/cmd_vel', '/r1_odom', '/r1/joint_states', '/quiet/cmd',
            '/skidbot/cmd_vel', '/skidbot/odom'} <= topics
    misplaced = {'/bot/cmd_vel', '/bot/odom', '/fleet/one/bot/cmd', '/quiet/odometry/wheels',
                 '/r1/cmd_vel', '/r1/odom', '/skidbot/joint_states'} & topics
    assert not misplaced
    odometry = {topic: ros.subscribe(Odometry, topic)
                for topic in ('/bot/odometry/wheels', '/fleet/one/odometry/wheels', '/r1_odom',
                              '/skidbot/odom')}
    joint_states = ros.subscribe(JointState, '/r1/joint_states')
    world.step()  # the state streams go out where steps end
    assert all(odometry.values()) and joint_states
    names = world.models()
    before = {name: world.state(name).pose for name in names}

    world.drive({'/bot/cmd': twist(linear_x=0.2), '/r1/drive/cmd_vel': twist(0.2),
                 '/quiet/cmd': twist(0.2), '/skidbot/cmd_vel': twist(0.2)}, 1.0)

    moved = {name: math.hypot(world.state(name).pose.position.x - before[name].position.x,
                              world.state(name).pose.position.y - before[name].position.y)
             for name in names}
    print(f'\nmoved on their own cmd topics, 0.2 m/s for 1 s: {moved}')
    for name in ('bot', 'r1', 'quiet', 'skid'):
        assert moved[name] == pytest.approx(0.2, rel=0.1), name
    assert moved['fleet_bot'] < 0.005 and moved['tinybot'] < 0.005
    wheels, r1_odometry = odometry['/bot/odometry/wheels'][-1], odometry['/r1_odom'][-1]
    assert (wheels.header.frame_id, wheels.child_frame_id) == ('bot_odom', 'base_footprint')
    assert r1_odometry.header.frame_id == 'r1_odom'
    assert r1_odometry.pose.pose.position.x == pytest.approx(0.2, rel=0.1)
    assert {'wheel_left_joint', 'wheel_right_joint'} <= set(joint_states[-1].name)
    # <covariance_x|y|yaw> on the diagonals of pose and twist; 1e12 for what is not measured.
    for odometry_msg, (x, y, yaw) in ((wheels, (0.0002, 0.0003, 0.004)),
                                      (odometry['/skidbot/odom'][-1], (0.0001, 0.0001, 0.01))):
        for matrix in (odometry_msg.pose.covariance, odometry_msg.twist.covariance):
            assert [matrix[7 * i] for i in range(6)] == [x, y, 1e12, 1e12, 1e12, yaw]
            assert sum(abs(value) for value in matrix) == pytest.approx(x + y + yaw + 3e12)

    assert world.delete('bot').success
    assert not {'/bot/cmd', '/bot/odometry/wheels'} & world.topics()


def test_xacro_with_find_and_arguments_through_the_client(paused_world, ros):
    path = os.path.join(TEST_MODELS, 'ros_mast_tinybot.urdf.xacro')
    spawned = spawn_client('--file', path, '--name', 'masted', '--namespace', 'masted',
                           '--xacro-arg', 'mast_height:=0.5', '-x', '2', '-y', '-2', '-z', '0.02',
                           '--yaw', '0')

    assert spawned.returncode == 0, spawned.stdout + spawned.stderr
    assert spawned.stdout == ('success: True\nstatus_message: '
                              '"SpawnModel: Successfully spawned entity \'masted\'"\n')
    model = paused_world.node.world.model
    [mast] = body_geoms(paused_world, 'masted::mast_link')
    assert model.geom_size[mast] == pytest.approx([0.005, 0.005, 0.25])
    before = settle(paused_world, 'masted').pose.position

    paused_world.drive({'/masted/cmd_vel': twist(linear_x=0.2)}, 1.0)
    after = paused_world.state('masted').pose.position
    assert after.x - before.x == pytest.approx(0.2, rel=0.1)


def test_a_xacro_file_not_named_xacro_spawns_with_what_was_left_out_named(paused_world):
    spawned = spawn_client('--file', os.path.join(TEST_MODELS, 'ros_gripper_parts.xml'),
                           '--name', 'gripper', '-z', '0.5')

    assert spawned.returncode == 0, spawned.stdout + spawned.stderr
    assert spawned.stdout == (
        'success: True\nstatus_message: "SpawnModel: Successfully spawned entity \'gripper\' '
        '(1 mesh not found, left out: meshes/ros_never_there.stl; '
        'plugins not simulated: libgazebo_ros_vacuum_gripper.so)"\n')
    assert paused_world.models() == ['tinybot', 'gripper']


def test_start_up_models_may_be_xacro_and_the_log_names_what_was_left_out(ros):
    log = ros.subscribe(Log, '/rosout', depth=1000)
    world = ros.start_world(
        paused=True,
        models=['tinybot.urdf', os.path.join(TEST_MODELS, 'ros_gripper_parts.xml'),
                os.path.join(TEST_MODELS, 'ros_mast_tinybot.urdf.xacro')],
        model_names=['tinybot', 'gripper', 'masted'], model_namespaces=['', '', 'masted'],
        model_poses=[0.0, 0.0, 0.0, 0.0, 2.0, 2.0, 0.5, 0.0, -2.0, -2.0, 0.02, 0.0])

    assert world.models() == ['tinybot', 'gripper', 'masted']
    assert '/masted/cmd_vel' in world.topics()
    # The world's log names each part it left out once, with the reason.
    left_out = [
        "model 'gripper': mesh 'meshes/ros_never_there.stl' cannot be had, so it is left out: "
        'no such file',
        "model 'gripper': plugin 'libgazebo_ros_vacuum_gripper.so' is not simulated here; it "
        'is ignored']
    assert ros.wait_for(lambda: any(entry.msg.startswith('MuJoCo world ready') for entry in log))
    world_log = [entry.msg for entry in log if entry.name == 'mujoco']
    assert [line for line in world_log if line in left_out] == left_out, world_log
    assert not any(line.startswith("model 'masted'") for line in world_log), world_log


def test_xacro_arguments_are_kept_from_rcl_which_takes_name_value_for_a_remapping():
    argv = ['spawn_model_client', '--xacro-arg', 'a:=1', '--file', 'f.xacro',
            '--xacro-arg', 'b:=x y', '--ros-args', '-r', 'c:=d', '--xacro-arg', 'e:=2']
    assert split_xacro_arguments(argv) == (
        ['spawn_model_client', '--file', 'f.xacro', '--ros-args', '-r', 'c:=d',
         '--xacro-arg', 'e:=2'], ['--xacro-arg=a:=1', '--xacro-arg=b:=x y'])
    assert split_xacro_arguments(['p', '--xacro-arg']) == (['p', '--xacro-arg'], [])


@pytest.mark.parametrize('arguments, reason', [
    ((os.path.join(TEST_MODELS, 'ros_unknown_package.urdf.xacro'),),
     "package 'no_such_package_xyz' not found"),
    ((os.path.join(TEST_MODELS, 'ros_mast_tinybot.urdf.xacro'), '--xacro-arg', 'mast_height'),
     "xacro argument 'mast_height' for "),
    ((os.path.join(TEST_MODELS, 'ros_mast_tinybot.urdf.xacro'), '--xacro-arg',
      'mast_height:=tall'), "when evaluating expression 'mast_height / 2'"),
])
def test_the_clients_xacro_errors_are_one_line_naming_the_file(arguments, reason):
    path = arguments[0]
    # No world is needed: the file is expanded before the service is asked.
    failed = spawn_client('--file', *arguments, '--timeout', '1')

    assert failed.returncode == 1
    assert failed.stdout == ''
    assert failed.stderr.startswith('spawn_model_client: ')
    assert failed.stderr.count('\n') == 1, failed.stderr
    assert f"'{path}'" in failed.stderr and reason in failed.stderr


def test_a_xacro_include_in_a_request_is_refused_and_never_read(paused_world, tmp_path):
    included = tmp_path / 'parts.xacro'
    included.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
                        '<link name="secret"/></robot>')
    request = ('<robot name="sneaky" xmlns:xacro="http://www.ros.org/wiki/xacro">'
               f'<xacro:include filename="{included}"/><link name="a"/></robot>')

    with FileOpens([str(included)], str(tmp_path)) as opens:
        response = paused_world.spawn('sneaky', request, make_pose(0.0, 3.0, 0.5))
    assert not response.success
    assert response.status_message == (
        'SpawnModel: model_xml contains xacro macros, which a spawn never expands: run xacro on '
        'it first, or name an installed .xacro file by its uri')
    assert opens.opened() == []
    assert paused_world.models() == ['tinybot']
