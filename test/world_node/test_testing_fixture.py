"""
The pytest fixture for users' tests (service_tutorial.testing): paused, exact, fresh, isolated.

A test of it is a user's test: it asks for mujoco_sim, steps the world and asserts what the
robot did. The README's example runs in test_readme_example.py, and once more here, as a user
runs it: alone, in a pytest of its own that never called rclpy.init() and takes none of this
run's options (colcon test's --pytest-args among them); and under pytest -n 2, where each
worker's world is on a graph of its own.
"""

import json
import math
import os
import re
import shutil
import subprocess
import sys
import textwrap
import threading

from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import pytest
import rclpy
from rclpy._rclpy_pybind11 import InvalidHandle
from rclpy.context import Context
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from repository import read_model, TEST_MODELS
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from service_tutorial.conversions import seconds_of
from service_tutorial.testing.simulated_world import SimulatedWorld, SimulationCallError
from service_tutorial.world_node.parameters import ParameterError
from simulation_interfaces.msg import Result, SimulationState
from simulation_interfaces.srv import GetSimulationState, SpawnEntity

pytest_plugins = ['service_tutorial.testing.fixtures']

HERE = os.path.dirname(os.path.abspath(__file__))
PROPS = os.path.join(TEST_MODELS, 'props')
# The paused world says its time again every 0.1 s of wall time: these many say it 0.4 s long.
REPEATED_CLOCKS = 5
# Participants a test made on the suite's own domain, kept until the process ends: Fast DDS 2.14
# can hang deleting one while another of the same process and domain sends it discovery data.
KEPT_TO_THE_END = []


def clock_messages(world):
    """Collect the simulation time of every /clock message the world sends from now on."""
    times = []
    world.node.create_subscription(Clock, '/clock', lambda msg: times.append(
        seconds_of(msg.clock)), 100)
    return times


def test_the_world_starts_paused_and_time_moves_only_by_step(mujoco_sim):
    assert mujoco_sim.simulation_state() == SimulationState.STATE_PAUSED
    assert mujoco_sim.time == 0.0
    # A command tinybot would follow at once in a playing world.
    cmd_vel = mujoco_sim.node.create_publisher(Twist, '/cmd_vel', 10)
    assert mujoco_sim.wait_for(lambda: cmd_vel.get_subscription_count() > 0)
    forward = Twist()
    forward.linear.x = 0.5
    cmd_vel.publish(forward)  # it lapses after cmd_vel_timeout, 0.5 s of simulation time
    times = clock_messages(mujoco_sim)
    assert mujoco_sim.wait_for(lambda: len(times) >= REPEATED_CLOCKS, timeout=10.0)
    assert set(times) == {0.0}, 'simulation time moved without step()'
    assert mujoco_sim.entity_state('tinybot').pose.position.x == pytest.approx(0.0, abs=1e-4)
    mujoco_sim.step(250)
    assert mujoco_sim.entity_state('tinybot').pose.position.x > 0.05, 'step() did not drive'


def test_a_command_published_just_before_step_acts_from_its_first_step(mujoco_sim):
    cmd_vel = mujoco_sim.node.create_publisher(Twist, '/cmd_vel', 10)
    assert mujoco_sim.wait_for(lambda: cmd_vel.get_subscription_count() > 0)
    drive = mujoco_sim.world_node.world.models['tinybot'].drive()
    command = Twist()
    for turn in range(1, 31):
        command.angular.z = 0.01 * turn  # each command a new one
        before = mujoco_sim.time
        cmd_vel.publish(command)
        mujoco_sim.step(1)
        # Taken by the world before the step, not by a tick after it.
        assert drive.commanded_at == pytest.approx(before, abs=mujoco_sim.timestep / 2), \
            f'command {turn} taken at {drive.commanded_at} s, not at {before} s'


@pytest.mark.parametrize('mujoco_sim, steps', [({}, 1), ({}, 7), ({'timestep': 0.005}, 40)],
                         indirect=['mujoco_sim'])
def test_step_moves_clock_by_exactly_n_timesteps(mujoco_sim, steps):
    times = clock_messages(mujoco_sim)
    start = mujoco_sim.time
    assert mujoco_sim.step(steps) == pytest.approx(start + steps * mujoco_sim.timestep, abs=1e-9)
    assert mujoco_sim.time == pytest.approx(start + steps * mujoco_sim.timestep, abs=1e-9)
    end = mujoco_sim.time
    assert mujoco_sim.wait_for(lambda: times and abs(times[-1] - end) < 1e-9)
    assert max(times) == pytest.approx(end, abs=1e-9), '/clock went past the steps asked for'
    stamp = mujoco_sim.entity_state('tinybot').header.stamp
    assert seconds_of(stamp) == pytest.approx(mujoco_sim.time, abs=1e-9)
    # And again from there: the steps add up, they do not start over.
    assert mujoco_sim.step(steps) == pytest.approx(start + 2 * steps * mujoco_sim.timestep,
                                                   abs=1e-9)


class OdometryListener(Node):
    """Keep the stamp of every odometry message, as a user's node that follows tinybot."""

    def __init__(self, **kwargs):
        super().__init__('odometry_listener', **kwargs)
        self.stamps = []
        self.odom_sub = self.create_subscription(Odometry, 'odom', self.odom_callback, 10)

    def odom_callback(self, odom):
        self.stamps.append(seconds_of(odom.header.stamp))


def test_step_returns_once_the_added_nodes_handled_what_the_steps_sent(mujoco_sim):
    listener = mujoco_sim.add_node(OdometryListener(context=mujoco_sim.context))
    assert mujoco_sim.wait_for(lambda: listener.count_publishers('/odom') > 0)
    for _ in range(50):
        mujoco_sim.step(10)  # tinybot's odometry comes every 10 steps (50 Hz)
        assert listener.stamps[-1] == pytest.approx(mujoco_sim.time, abs=1e-9)


class BrokenOdometryListener(OdometryListener):
    """A user's node with a bug: its odometry callback raises."""

    def odom_callback(self, odom):
        raise ArithmeticError(f'odometry at {seconds_of(odom.header.stamp):.2f} s')


def test_what_a_node_of_the_test_raises_comes_out_of_step(mujoco_sim):
    mujoco_sim.add_node(BrokenOdometryListener(context=mujoco_sim.context))
    # The first odometry it takes is the one of 0 s or of 0.02 s: whether the world has heard
    # of the new subscriber before its first update is the middleware's business.
    with pytest.raises(ArithmeticError, match=r'odometry at 0\.0[02] s') as raised:
        mujoco_sim.step(10)
    with pytest.raises(ArithmeticError, match=str(raised.value)):  # the node stopped there
        mujoco_sim.step(10)


@pytest.mark.parametrize('run', ['first', 'second'])
def test_each_test_gets_a_fresh_world(mujoco_sim, run):
    # Whichever of the two runs second would see what the first left behind.
    assert mujoco_sim.time == 0.0
    assert mujoco_sim.get_entities() == ['tinybot']
    assert mujoco_sim.entity_state('tinybot').pose.position.x == pytest.approx(0.0, abs=1e-4)
    mujoco_sim.spawn_entity(f'crate_{run}', read_model('red_box', PROPS), (2.0, 2.0, 0.5))
    mujoco_sim.set_entity_state('tinybot', (1.0, 0.0, 0.1))
    mujoco_sim.step(50)
    assert sorted(mujoco_sim.get_entities()) == sorted(['tinybot', f'crate_{run}'])


def test_the_world_is_on_a_graph_of_its_own(mujoco_sim_factory, ros):
    # ros: a node of the suite's own rclpy Context, on the process's default domain.
    world = mujoco_sim_factory(namespace='isolated')
    default_domain = ros.client_node.context.get_domain_id()
    assert world.context.get_domain_id() not in (default_domain, 0)
    assert world.wait_for(lambda: ('mujoco', '/isolated') in
                          world.node.get_node_names_and_namespaces()), 'the world is not up'
    # A participant of the default domain that came after the world: once it is seen, the world
    # would have been seen too, were it on the same graph.
    beacon_context = Context()
    rclpy.init(context=beacon_context, domain_id=default_domain,
               signal_handler_options=SignalHandlerOptions.NO)
    beacon = Node('beacon_on_the_default_domain', context=beacon_context)
    KEPT_TO_THE_END.append((beacon_context, beacon))
    assert ros.wait_for(lambda: (beacon.get_name(), '/') in
                        ros.client_node.get_node_names_and_namespaces())
    seen = ros.client_node.get_node_names_and_namespaces()
    assert ('mujoco', '/isolated') not in seen
    assert ('simulation_test_client', '/') not in seen
    outsider = ros.client_node.create_client(GetSimulationState,
                                             '/isolated/get_simulation_state')
    assert not outsider.service_is_ready()
    # And the world answers its own graph all along.
    assert world.simulation_state() == SimulationState.STATE_PAUSED


def test_the_sensors_publish_from_the_world_node_the_domains_one_participant(mujoco_sim):
    # In a context of its own, the world takes no second participant for its sensors
    # (world_node/participants.py): tinybot's /scan comes from the node mujoco itself.
    scans = []
    mujoco_sim.node.create_subscription(LaserScan, '/scan', scans.append, 10)
    mujoco_sim.step(round(0.2 / mujoco_sim.timestep) + 1)  # the laser scans at 5 Hz

    assert mujoco_sim.wait_for(lambda: scans), 'no scan came'
    publishers = mujoco_sim.node.get_publishers_info_by_topic('/scan')
    assert [(info.node_namespace, info.node_name) for info in publishers] == [('/', 'mujoco')]
    assert mujoco_sim.world_node.sensor_node.publishers == []


def test_two_worlds_at_once_do_not_see_each_other(mujoco_sim_factory):
    first, second = mujoco_sim_factory(), mujoco_sim_factory(timestep=0.001)
    assert first.domain_id != second.domain_id
    first.step(10)
    assert (first.time, second.time) == (pytest.approx(0.02), 0.0)
    second.spawn_entity('r2d2', 'package://service_tutorial/models/r2d2.urdf', (-2, 1, 1))
    assert first.get_entities() == ['tinybot']


def test_a_closed_world_leaves_no_thread_and_no_context():
    threads = set(threading.enumerate())
    world = SimulatedWorld()
    node = world.add_node(Node('user_node', context=world.context))
    world.step(3)
    world.close()
    assert set(threading.enumerate()) == threads
    assert not world.context.ok()
    with pytest.raises(InvalidHandle, match='destruction was requested'):
        node.get_node_names()  # the test's own node went with the world


def test_a_bad_world_parameter_is_refused_and_leaves_nothing_behind():
    threads = set(threading.enumerate())
    with pytest.raises(ParameterError, match='timestep'):
        SimulatedWorld(timestep=-1.0)
    assert set(threading.enumerate()) == threads


def test_bad_steps_are_refused_naming_them_and_the_world_stays(mujoco_sim):
    for steps in (0, -3, 2.5, True, '10', None):
        with pytest.raises(ValueError, match=repr(steps).replace('.', r'\.')):
            mujoco_sim.step(steps)
    assert mujoco_sim.time == 0.0
    assert mujoco_sim.step(2) == pytest.approx(0.004)


def test_a_bad_pose_is_refused_naming_it_and_nothing_is_spawned(mujoco_sim):
    crate = read_model('red_box', PROPS)
    with pytest.raises(ValueError, match=re.escape('(1.0, 2.0)')):
        mujoco_sim.spawn_entity('crate', crate, (1.0, 2.0))
    with pytest.raises(SimulationCallError, match='nan') as refusal:
        mujoco_sim.spawn_entity('crate', crate, (math.nan, 0.0, 0.0))
    assert refusal.value.code == SpawnEntity.Response.INVALID_POSE
    assert mujoco_sim.get_entities() == ['tinybot']


def test_refusals_of_the_world_raise_with_its_code_and_message(mujoco_sim):
    with pytest.raises(SimulationCallError, match='nobody') as refusal:
        mujoco_sim.delete_entity('nobody')
    assert refusal.value.code == Result.RESULT_NOT_FOUND
    mujoco_sim.set_simulation_state(SimulationState.STATE_PLAYING)
    with pytest.raises(SimulationCallError) as refusal:
        mujoco_sim.step(5)
    assert refusal.value.code == Result.RESULT_OPERATION_FAILED
    mujoco_sim.set_simulation_state(SimulationState.STATE_STOPPED)
    assert mujoco_sim.time == 0.0
    assert mujoco_sim.step(5) == pytest.approx(0.01)


def test_a_node_of_another_context_is_refused_naming_it(mujoco_sim, ros):
    stranger = Node('stranger', context=ros.client_node.context)
    try:
        with pytest.raises(ValueError, match='/stranger'):
            mujoco_sim.add_node(stranger)
    finally:
        stranger.destroy_node()


def test_reset_puts_the_world_back_at_its_start(mujoco_sim):
    mujoco_sim.spawn_entity('r2d2', 'package://service_tutorial/models/r2d2.urdf', (-2, 1, 1))
    mujoco_sim.set_entity_state('tinybot', (1.0, 2.0, 0.1, 1.57))
    mujoco_sim.step(100)
    mujoco_sim.reset()
    assert mujoco_sim.time == 0.0
    assert mujoco_sim.get_entities() == ['tinybot']
    assert mujoco_sim.entity_state('tinybot').pose.position.y == pytest.approx(0.0, abs=1e-4)


def run_pytest_as_a_user(folder, *arguments, timeout):
    """Run pytest in folder as a user starts it, with none of this run's settings; return it."""
    # This run's settings are not the user's: colcon test hands its options (--pytest-args,
    # its junit file and cache folder) over in PYTEST_ADDOPTS, and pytest-xdist tells its
    # workers who they are in PYTEST_XDIST_WORKER.
    environment = {name: value for name, value in os.environ.items()
                   if not name.startswith('PYTEST_')}
    return subprocess.run(
        [sys.executable, '-m', 'pytest', '-q', '-p', 'no:cacheprovider', *arguments],
        cwd=folder, env=environment, capture_output=True, text=True, timeout=timeout)


def test_the_readme_example_runs_alone_as_a_user_runs_it(tmp_path, monkeypatch):
    # A folder of its own: no conftest.py of this suite, no rclpy.init() before the fixture.
    user_folder = tmp_path / 'user'
    user_folder.mkdir()
    shutil.copy(os.path.join(HERE, 'test_readme_example.py'), user_folder / 'test_my_node.py')
    # This run's options as `colcon test --pytest-args -k runs_alone` gives them: taken by the
    # user's run, they would select nothing there and write colcon's junit file.
    colcon = tmp_path / 'build'
    monkeypatch.setenv('PYTEST_ADDOPTS', f'--tb=short --junit-xml={colcon}/pytest.xml '
                       f'--junit-prefix=service_tutorial -o cache_dir={colcon}/.pytest_cache '
                       '-k runs_alone')
    finished = run_pytest_as_a_user(user_folder, 'test_my_node.py', timeout=300)
    assert finished.returncode == 0, finished.stdout[-3000:] + finished.stderr[-3000:]
    assert '1 passed' in finished.stdout
    assert not colcon.exists(), "the user's run took this run's options"


# A user's test module for pytest -n 2: its two tests, one on each worker, spawn the same names
# in worlds of their own, and each looks at its world while the other's is up with the same
# names. Were the two worlds on one graph, a spawn, a list or a pose would reach the wrong one.
TWO_WORKERS = textwrap.dedent('''\
    """Two tests on two workers: the same names spawned, each world seen only by its own test."""

    import json
    import os
    import pathlib

    import pytest

    pytest_plugins = ['service_tutorial.testing.fixtures']

    MEETING = pathlib.Path(__file__).parent / 'meeting'
    R2D2 = 'package://service_tutorial/models/r2d2.urdf'


    def both(suffix):
        return len(list(MEETING.glob('*' + suffix))) == 2


    @pytest.mark.parametrize('x', [2.0, -2.0])
    def test_a_world_of_its_own(mujoco_sim, x):
        worker = os.environ['PYTEST_XDIST_WORKER']
        mujoco_sim.set_entity_state('tinybot', (x, 0.0, 0.1))
        mujoco_sim.spawn_entity('r2d2', R2D2, (x, 1.0, 1.0))
        (MEETING / f'{worker}.json').write_text(
            json.dumps({'domain_id': mujoco_sim.domain_id, 'x': x}))
        assert mujoco_sim.wait_for(lambda: both('.json'), timeout=60.0), 'the other never came'
        mujoco_sim.step(10)
        assert sorted(mujoco_sim.get_entities()) == ['r2d2', 'tinybot']
        for name in ('tinybot', 'r2d2'):
            assert mujoco_sim.entity_state(name).pose.position.x == pytest.approx(x, abs=0.01)
        (MEETING / f'{worker}.done').touch()
        assert mujoco_sim.wait_for(lambda: both('.done'), timeout=60.0), 'the other never looked'
''')


@pytest.mark.long
def test_under_pytest_xdist_each_worker_has_worlds_of_its_own_on_its_own_domain(tmp_path):
    user_folder = tmp_path / 'user'
    meeting = user_folder / 'meeting'
    meeting.mkdir(parents=True)
    (user_folder / 'test_two_workers.py').write_text(TWO_WORKERS)
    finished = run_pytest_as_a_user(user_folder, '-n', '2', 'test_two_workers.py', timeout=120)
    assert finished.returncode == 0, finished.stdout[-3000:] + finished.stderr[-3000:]
    assert '2 passed' in finished.stdout
    worlds = {path.stem: json.loads(path.read_text()) for path in meeting.glob('*.json')}
    assert sorted(worlds) == ['gw0', 'gw1'], 'the two tests did not run on two workers'
    assert worlds['gw0']['domain_id'] != worlds['gw1']['domain_id']
    assert sorted(world['x'] for world in worlds.values()) == [-2.0, 2.0]
