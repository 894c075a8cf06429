"""
create, as a Gazebo launch file runs ros_gz_sim's: a robot from -file, -string or -topic.

The program is the point (its command line and exit status), so it runs as an installed
executable against a world of its own (SimulatedWorld, paused); its flag parser is tested in
this process too.
"""

import os
import subprocess

from ament_index_python.packages import get_package_share_directory
from programs import program_path
import pytest
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from repository import read_model, TEST_MODELS
from service_tutorial.ros_gz.create import CreateArgumentError, file_uri, parse_flags
from service_tutorial.testing.simulated_world import SimulatedWorld
from std_msgs.msg import String
import yaml

# Wall time the program may take (start-up, discovery, the spawn), in s.
RUN_TIMEOUT = 60
LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)


@pytest.fixture(scope='module')
def world():
    """Start a paused world on a graph of its own, for this file's runs (distinct names)."""
    simulated = SimulatedWorld()
    yield simulated
    simulated.close()


def run_create(world, *args):
    """Run the installed create against world; return the finished process."""
    environment = dict(os.environ, ROS_DOMAIN_ID=str(world.domain_id),
                       ROS_AUTOMATIC_DISCOVERY_RANGE='LOCALHOST')
    return subprocess.run([program_path('create'), *args], env=environment,
                          capture_output=True, text=True, timeout=RUN_TIMEOUT)


def position(world, name):
    point = world.entity_state(name).pose.position
    return (round(point.x, 6), round(point.y, 6), round(point.z, 6))


def test_create_file_spawns_an_installed_robot_at_its_pose(world):
    tinybot = os.path.join(get_package_share_directory('service_tutorial'), 'models',
                           'tinybot.urdf')
    done = run_create(world, '-name', 'from_file', '-file', tinybot,
                      '-x', '1.5', '-y', '-2', '-z', '0.25', '-Y', '1.0')
    assert done.returncode == 0, done.stderr
    assert position(world, 'from_file') == (1.5, -2.0, 0.25)
    orientation = world.entity_state('from_file').pose.orientation
    assert orientation.z == pytest.approx(0.479426, abs=1e-6)  # sin(0.5): yaw 1 rad


def test_create_string_spawns_the_xml_given_as_a_ros_parameter_as_a_launch_file_gives_it(
        world, tmp_path):
    parameters = tmp_path / 'create.yaml'
    parameters.write_text(yaml.safe_dump({'ros_gz_sim': {'ros__parameters': {
        'string': read_model('gzbot', TEST_MODELS), 'name': 'from_string', 'x': 3.0}}}))
    done = run_create(world, '--ros-args', '--params-file', str(parameters), '-p', 'y:=0.5')
    assert done.returncode == 0, done.stderr
    assert position(world, 'from_string')[:2] == (3.0, 0.5)


def test_create_topic_takes_the_latched_robot_description(world):
    node = world.add_node(Node('robot_state_publisher', context=world.context))
    publisher = node.create_publisher(String, 'robot_description', LATCHED)
    publisher.publish(String(data=read_model('gzbot', TEST_MODELS)))
    done = run_create(world, '-topic', 'robot_description', '-name', 'from_topic',
                      '-entity', 'ignored', '-robot_namespace', '', '-y', '4')
    assert done.returncode == 0, done.stderr
    assert position(world, 'from_topic')[:2] == (0.0, 4.0)
    assert 'create ignores what it does not know: -entity ignored -robot_namespace' in \
        done.stderr


def test_a_refused_spawn_exits_1_with_the_worlds_reason(world):
    urdf = read_model('gzbot', TEST_MODELS)
    assert run_create(world, '-string', urdf, '-name', 'twice').returncode == 0
    again = run_create(world, '-string', urdf, '-name', 'twice')
    assert again.returncode == 1
    assert 'create: the world did not spawn it: ' in again.stderr and 'twice' in again.stderr
    # -allow_renaming true, as launch files write it, takes the next free name.
    renamed = run_create(world, '-string', urdf, '-name', 'twice', '-allow_renaming', 'true')
    assert renamed.returncode == 0, renamed.stderr
    assert "spawned 'twice_" in renamed.stderr
    outside = run_create(world, '-file', '/etc/hostname')
    assert outside.returncode == 1
    assert 'outside the share folders of the installed packages' in outside.stderr
    # The rule is the world's: create says it, and what a user can do instead.
    assert 'create: note: -file is read by the world' in outside.stderr
    assert '-string "$(cat FILE)"' in outside.stderr
    assert 'note' not in run_create(world, '-file', 'file:///etc/hostname').stderr


def test_create_without_a_robot_or_with_another_world_exits_1_saying_why(world):
    nothing = run_create(world, '-name', 'nothing')
    assert nothing.returncode == 1
    assert 'give the robot with -file, -param, -string or -topic' in nothing.stderr
    elsewhere = run_create(world, '-world', 'mars', '-string', read_model('gzbot', TEST_MODELS))
    assert elsewhere.returncode == 1
    assert "no world named 'mars'" in elsewhere.stderr


@pytest.mark.parametrize('arguments, flags, ignored', [
    (['-name', 'a', '-x', '-2.0', '--y', '3', '-z=0.5'],
     {'name': 'a', 'x': -2.0, 'y': 3.0, 'z': 0.5}, []),
    (['-allow_renaming', '-file', 'm.sdf'], {'allow_renaming': True, 'file': 'm.sdf'}, []),
    (['-allow_renaming', 'false'], {'allow_renaming': False}, []),
    (['-allow_renaming=true'], {'allow_renaming': True}, []),
    (['-entity', 'tb3', '-robot_namespace', '', '-R', '0.1'], {'R': 0.1},
     ['-entity', 'tb3', '-robot_namespace', '']),
])
def test_create_reads_its_flags_as_its_flag_parser_does(arguments, flags, ignored):
    assert parse_flags(arguments) == (flags, ignored)


@pytest.mark.parametrize('arguments, said', [
    (['-x', 'far'], "-x takes a number, not 'far'"),
    (['-name'], '-name needs a value'),
    (['-allow_renaming=maybe'], "-allow_renaming takes true or false, not 'maybe'"),
])
def test_a_bad_flag_value_is_named(arguments, said):
    with pytest.raises(CreateArgumentError, match=said):
        parse_flags(arguments)


def test_a_file_is_sent_as_a_uri_made_absolute():
    assert file_uri('model://burger') == 'model://burger'
    assert file_uri('m.sdf') == 'file://' + os.path.join(os.getcwd(), 'm.sdf')
