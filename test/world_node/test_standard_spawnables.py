"""
The standard's GetSpawnables through a real client on the running world.

This package's robots by package:// uri with their drives, sensors and bounds; a TurtleBot3-style
xacro package installed in tmp, offered and spawned by its uri and driven; sources that add
folders; hostile sources and robot files named in the message, nothing outside the roots read.
"""

import os
import shutil

from file_opens import FileOpens
from geometry_msgs.msg import Twist
import pytest
from repository import install_package, TEST_MODELS
from simulation_interfaces.msg import Bounds, Result, SimulatorFeatures
from simulation_interfaces.srv import GetEntityBounds, GetSimulatorFeatures, GetSpawnables
from simulation_interfaces.srv import StepSimulation
from standard_entities import close, CRATE, position_of, spawn_or_fail, stamped

pytestmark = pytest.mark.ros

TINYBOT_URI = 'package://service_tutorial/models/tinybot.urdf'
R2D2_URI = 'package://service_tutorial/models/r2d2.urdf'
MY_ROBOT_URI = 'package://my_description/urdf/robot.urdf.xacro'
PROPERTIES_URI = 'package://my_description/urdf/common_properties.xacro'
PENDULUM = ('<mujoco model="pendulum"><worldbody><body name="arm" pos="0 0 1">'
            '<joint name="swing" type="hinge" axis="0 1 0"/>'
            '<geom type="box" size="0.05 0.1 0.3" pos="0 0 -0.3" mass="1"/>'
            '</body></worldbody><actuator><motor joint="swing"/></actuator>'
            '<sensor><jointpos joint="swing"/></sensor></mujoco>')


def step(world, steps):
    """Step the paused world with StepSimulation; fail if it does not."""
    result = world.call(StepSimulation, '/step_simulation',
                        StepSimulation.Request(steps=steps), timeout=60.0).result
    assert result.result == Result.RESULT_OK, result.error_message


def spawnables(world, sources=(), *, timeout=30.0):
    """Call /get_spawnables; return the response."""
    return world.call(GetSpawnables, '/get_spawnables',
                      GetSpawnables.Request(sources=list(sources)), timeout=timeout)


def offered(response):
    """Return {uri: Spawnable} of a response, checking that it answered OK."""
    assert response.result.result == Result.RESULT_OK, response.result.error_message
    return {spawnable.uri: spawnable for spawnable in response.spawnables}


def corners(bounds):
    """Return the two corners of a BOX Bounds as ((x, y, z), (x, y, z))."""
    assert bounds.type == Bounds.TYPE_BOX
    return tuple((point.x, point.y, point.z) for point in bounds.points)


def entity_corners(world, name):
    """Return the corners of GetEntityBounds of a spawned entity."""
    response = world.call(GetEntityBounds, '/get_entity_bounds',
                          GetEntityBounds.Request(entity=name))
    assert response.result.result == Result.RESULT_OK, response.result.error_message
    return corners(response.bounds)


def same_box(first, second, tolerance=1e-6):
    return close(first[0] + first[1], second[0] + second[1], tolerance)


@pytest.fixture
def my_description(tmp_path, monkeypatch):
    """
    Install a TurtleBot3-style package my_description in tmp, through AMENT_PREFIX_PATH.

    urdf/ holds robot.urdf.xacro and common_properties.xacro (test/models/my_description), an
    MJCF pendulum and a file that is XML but not MJCF; extra/ a crate read only as a source;
    outside/, beside the prefix, the files a leaky search would read.
    """
    share = install_package(tmp_path, monkeypatch, 'my_description')
    shutil.copytree(os.path.join(TEST_MODELS, 'my_description'), share, dirs_exist_ok=True)
    (share / 'mjcf').mkdir()
    (share / 'mjcf' / 'pendulum.xml').write_text(PENDULUM)
    (share / 'urdf' / 'package.xml').write_text('<package format="3"><name>x</name></package>')
    (share / 'extra').mkdir()
    (share / 'extra' / 'crate.urdf').write_text(CRATE)
    outside = tmp_path / 'outside'
    outside.mkdir()
    return share, outside


def test_the_feature_is_claimed(ros):
    world = ros.start_world(paused=True)
    features = world.call(GetSimulatorFeatures, '/get_simulator_features',
                          GetSimulatorFeatures.Request()).features
    assert SimulatorFeatures.SPAWNABLES in features.features


def test_this_packages_robots_are_offered_with_drives_sensors_and_bounds(ros):
    world = ros.start_world(paused=True, real_time_factor=0.0)
    model, data, time_before = world.node.world.model, world.node.world.data, world.now()
    response = spawnables(world)
    robots = offered(response)
    assert {TINYBOT_URI, R2D2_URI} <= set(robots)
    # Compiled alone: the world's model and data are the ones it had, its time where it was.
    assert world.node.world.model is model and world.node.world.data is data
    assert world.node.world.time == time_before and world.models() == ['tinybot']
    # The yard is the world's scenery, already there: not offered.
    assert 'package://service_tutorial/models/yard.urdf' not in robots
    tinybot = robots[TINYBOT_URI].description
    assert tinybot == ('tinybot: a diff-drive on cmd_vel, odom, joint_states; a laser on scan; '
                       'a camera on camera/image_raw, camera/camera_info; an IMU on imu')
    assert robots[R2D2_URI].description == 'r2d2: no drive or sensors'
    # tinybot's URDF: chassis radius 0.085, wheels' outer faces at 0.133, top at 0.093.
    assert same_box(corners(robots[TINYBOT_URI].spawn_bounds),
                    ((-0.085, -0.133, 0.0), (0.085, 0.133, 0.093)))
    assert same_box(corners(robots[TINYBOT_URI].spawn_bounds), entity_corners(world, 'tinybot'))
    # R2-D2 spawned by the uri offered has the bounds offered.
    assert spawn_or_fail(world, uri=R2D2_URI, initial_pose=stamped(-2.0, 1.0, 1.0)) == 'r2d2'
    assert same_box(corners(robots[R2D2_URI].spawn_bounds), entity_corners(world, 'r2d2'))
    assert same_box(corners(robots[R2D2_URI].spawn_bounds),
                    ((-0.21, -0.33, 0.0), (0.21, 0.33, 1.12)))


def test_an_installed_turtlebot3_xacro_is_offered_spawns_and_drives(ros, my_description):
    # Paused, stepped by StepSimulation: the drive is measured in simulation time, and a command
    # lasts the whole drive (cmd_vel_timeout 10 s).
    world = ros.start_world(paused=True, real_time_factor=0.0, cmd_vel_timeout=10.0)
    response = spawnables(world)
    robots = offered(response)
    assert robots[MY_ROBOT_URI].description == \
        'my_robot: a diff-drive on cmd_vel, odom, joint_states'
    # Base box 0.14 x 0.14 x 0.12 at (-0.032, 0, 0.08) of base_footprint; wheels of radius
    # 0.033 and width 0.018 at y = +-0.08 (the default wheel_separation), touching z = 0.
    lower, upper = corners(robots[MY_ROBOT_URI].spawn_bounds)
    assert close(lower, (-0.102, -0.089, 0.0), 1e-3) and close(upper, (0.038, 0.089, 0.14), 1e-3)
    # Properties only: no robot; named in the message, which says the answer is still whole.
    assert PROPERTIES_URI not in robots
    message = response.result.error_message
    assert f'{PROPERTIES_URI}: it has no links: it is macros or properties' in message
    # The MJCF pendulum is offered with its name, actuator and joint states; package.xml is no
    # robot. Its bounds are in the frame of its top body, as a spawned entity's are: the arm
    # (at z = 1 in its file) hangs 0.6 m below its hinge.
    assert robots['package://my_description/mjcf/pendulum.xml'].description == \
        'pendulum: MJCF, 1 actuators; a joint state publisher on joint_states; fixed to the world'
    assert same_box(corners(robots['package://my_description/mjcf/pendulum.xml'].spawn_bounds),
                    ((-0.05, -0.1, -0.6), (0.05, 0.1, 0.0)))
    assert not any('package.xml' in uri for uri in robots) and 'package.xml' not in message
    # extra/ is no robot folder: its crate only comes as a source.
    assert 'package://my_description/extra/crate.urdf' not in robots

    assert spawn_or_fail(world, name='burger', uri=MY_ROBOT_URI, entity_namespace='burger',
                         initial_pose=stamped(0.0, 2.0, 0.02)) == 'burger'
    # The same box as the spawned entity's, up to its wheels turning a little as it landed.
    assert same_box(corners(robots[MY_ROBOT_URI].spawn_bounds), entity_corners(world, 'burger'),
                    1e-4)
    step(world, 500)  # 1 s to land and rest
    before = position_of(world, 'burger')
    command = Twist()
    command.linear.x = 0.1
    # Taken by the world before the steps (at a tick of the paused world), so that it acts
    # from their first: 2 s of simulation time, however late it came in wall time.
    world.command('/burger/cmd_vel', command)
    world.step(1000)
    after = position_of(world, 'burger')
    print(f'\nmy_robot driven at 0.1 m/s for 2 s: from {before} to {after}')
    assert after[0] - before[0] == pytest.approx(0.2, abs=0.01)
    assert abs(after[1] - before[1]) < 0.03


def test_sources_add_their_robot_files(ros, my_description):
    share, _ = my_description
    world = ros.start_world(paused=True)
    crate_uri = 'package://my_description/extra/crate.urdf'
    for source in ('package://my_description/extra', f'file://{share}/extra',
                   'package://my_description/extra/'):
        robots = offered(spawnables(world, [source]))
        assert robots[crate_uri].description == 'crate: no drive or sensors', source
        assert TINYBOT_URI in robots and MY_ROBOT_URI in robots
        assert same_box(corners(robots[crate_uri].spawn_bounds),
                        ((-0.2, -0.2, -0.2), (0.2, 0.2, 0.2)))
    assert spawn_or_fail(world, uri=crate_uri, initial_pose=stamped(3.0, 0.0, 0.3)) == 'crate'


def test_hostile_sources_are_named_and_nothing_outside_the_roots_is_read(ros, my_description):
    share, outside = my_description
    world = ros.start_world(paused=True)
    (outside / 'secret.urdf').write_text(CRATE)
    (outside / 'mesh.obj').write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n')
    (share / 'linked').symlink_to(outside)
    (share / 'urdf' / 'escape.urdf').symlink_to(outside / 'secret.urdf')
    (share / 'urdf' / 'linked_folder').symlink_to(outside)  # a folder link: never followed
    refused = [
        ('/etc', "source '/etc' is neither package://<package>/<path> nor file://"),
        ('file:///etc', "source 'file:///etc' lies outside the share folders"),
        (f'file://{outside}', 'lies outside the share folders'),
        ('file:///tmp/../etc', "source 'file:///tmp/../etc' must not contain '..'"),
        (f'file://{share}/../../..', "must not contain '..'"),
        ('package://my_description/../..', "must not contain '..'"),
        ('package://my_description/linked', "source 'package://my_description/linked' leads "
         'outside the share folder of its package'),
        (f'file://{share}/linked', 'leads outside the share folder of its package'),
        ('http://example.com/robots', "source 'http://example.com/robots' is neither"),
        ('package://no_such_package/urdf', "package 'no_such_package' is not installed"),
        ('package://my_description/nowhere', 'names no folder'),
        (MY_ROBOT_URI, 'names no folder'),
        ('x' * 10000, 'is longer than 4096 characters'),
    ]
    with FileOpens([str(outside / 'secret.urdf'), str(outside / 'mesh.obj')],
                   str(outside)) as opens:
        response = spawnables(world, [source for source, _ in refused])
    robots = offered(response)
    message = response.result.error_message
    for source, reason in refused:
        assert reason in message, source
    assert len(message) < 6000
    assert opens.opened() == []
    # The defaults are still answered; nothing outside the roots is offered.
    assert {TINYBOT_URI, MY_ROBOT_URI} <= set(robots)
    assert all(uri.startswith('package://') and 'linked' not in uri and 'secret' not in uri
               for uri in robots)
    assert 'secret' not in message
    assert ('package://my_description/urdf/escape.urdf: it is a link that leads outside the share '
            'folder of its package') in message

    many = spawnables(world, ['package://my_description/extra'] * 40)
    assert offered(many)
    assert '40 sources are more than 32; the 8 after the first 32 are not read' in \
        many.result.error_message


def test_malformed_huge_and_escaping_robot_files_are_left_out_with_a_note(ros, my_description):
    share, outside = my_description
    world = ros.start_world(paused=True)
    (outside / 'secret.obj').write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n')
    urdf = share / 'urdf'
    (urdf / 'broken.urdf').write_text('<robot name="broken"><link name=')
    (urdf / 'huge.urdf').write_bytes(b'<robot name="huge">' + b' ' * (11 * 1024 * 1024)
                                     + b'</robot>')
    (urdf / 'no_wheels.urdf.xacro').write_text(
        '<robot name="nw" xmlns:xacro="http://www.ros.org/wiki/xacro">'
        '<xacro:wheel side="left"/></robot>')
    mjcf = share / 'mjcf'
    (mjcf / 'peeking.xml').write_text(
        f'<mujoco><asset><mesh file="{outside}/secret.obj"/></asset><worldbody>'
        '<geom type="mesh" mesh="secret"/></worldbody></mujoco>')
    (mjcf / 'climbing.xml').write_text(
        '<mujoco><compiler meshdir="../../../../outside"/><asset><mesh file="secret.obj"/>'
        '</asset><worldbody><geom type="mesh" mesh="secret"/></worldbody></mujoco>')
    (mjcf / 'including.xml').write_text(
        f'<mujoco><include file="{outside}/secret.obj"/></mujoco>')
    with FileOpens([str(outside / 'secret.obj')], str(outside)) as opens:
        response = spawnables(world)
    robots = offered(response)
    message = response.result.error_message
    assert MY_ROBOT_URI in robots and TINYBOT_URI in robots
    assert opens.opened() == []
    assert '7 robot files are left out: ' in message, message
    for name, reason in [('urdf/broken.urdf', 'does not parse as XML'),
                         ('urdf/huge.urdf', 'is larger than the limit of 10485760 bytes')]:
        uri = f'package://my_description/{name}'
        assert f"{uri}: uri '{uri}' {reason}" in message
    for name in ('broken.urdf', 'huge.urdf', 'no_wheels.urdf.xacro', 'common_properties.xacro',
                 'peeking.xml', 'climbing.xml', 'including.xml'):
        assert not any(uri.endswith(name) for uri in robots), name
    # Asked again, the files are not read again: the answer is the same and quick.
    again = spawnables(world, timeout=5.0)
    assert offered(again).keys() == robots.keys()
    assert again.result.error_message == message


def test_a_repeated_call_reads_no_robot_file_again(ros, monkeypatch):
    from service_tutorial.world_node.standard.spawnables import SpawnableServices
    world = ros.start_world(paused=True)
    first = spawnables(world)
    reader = next(group for group in world.node.standard_groups
                  if isinstance(group, SpawnableServices)).reader
    read_new, reads = reader._read_new, []
    monkeypatch.setattr(reader, '_read_new', lambda uri, path: (
        reads.append(uri), read_new(uri, path))[1])
    again = spawnables(world)
    # What made the first call slow (reading, building and compiling each robot) is not done
    # again: the answer is the one kept, the same.
    assert reads == []
    assert offered(again) == offered(first) and TINYBOT_URI in offered(again)


def test_files_left_for_a_next_call_are_counted_and_come_then(ros, monkeypatch):
    from service_tutorial.world_node.standard import spawnables as spawnables_module
    world = ros.start_world(paused=True)
    monkeypatch.setattr(spawnables_module, 'READING_SECONDS', -1.0)
    response = spawnables(world)
    assert response.result.result == Result.RESULT_OK
    assert TINYBOT_URI not in offered(response)
    assert 'robot files are not read yet: reading new files takes at most -1 s a call; ask ' \
        'again for them' in response.result.error_message
    monkeypatch.setattr(spawnables_module, 'READING_SECONDS', 5.0)
    assert TINYBOT_URI in offered(spawnables(world))
