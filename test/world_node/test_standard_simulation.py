"""
The standard's simulation state, resets, stepping and features, through the standard's types.

A test client calls the running world as any tool written against simulation_interfaces would:
/get_simulation_state, /set_simulation_state, /reset_simulation, /step_simulation, the
/simulate_steps action and /get_simulator_features, beside the lesson's /mujoco/ services.
"""

import math
import time

from action_msgs.msg import GoalStatus
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import numpy as np
import pytest
from repository import read_file, TINYBOT
from service_tutorial.conversions import make_pose, seconds_of
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
from simulation_interfaces.srv import GetSimulationState, GetSimulatorFeatures
from simulation_interfaces.srv import ResetSimulation, SetSimulationState, StepSimulation

pytestmark = pytest.mark.ros

STOPPED = SimulationState.STATE_STOPPED
PLAYING = SimulationState.STATE_PLAYING
PAUSED = SimulationState.STATE_PAUSED
QUITTING = SimulationState.STATE_QUITTING
OK = Result.RESULT_OK
FAILED = Result.RESULT_OPERATION_FAILED
ALREADY = SetSimulationState.Response.ALREADY_IN_TARGET_STATE
INCORRECT = SetSimulationState.Response.INCORRECT_TRANSITION
TIMESTEP = 0.002
LONGEST = 2 ** 64 - 1  # the largest uint64


def state(world):
    """Return the simulation state as GetSimulationState says it."""
    response = world.call(GetSimulationState, '/get_simulation_state',
                          GetSimulationState.Request())
    assert response.result.result == OK, response.result.error_message
    return response.state.state


def set_state(world, target):
    """Ask for a simulation state; return the Result."""
    return world.call(SetSimulationState, '/set_simulation_state', SetSimulationState.Request(
        state=SimulationState(state=target))).result


def reset(world, scope):
    """Reset the simulation with a scope; return the Result."""
    return world.call(ResetSimulation, '/reset_simulation',
                      ResetSimulation.Request(scope=scope)).result


def step(world, steps=None, *, timeout=60.0):
    """Step the simulation with StepSimulation (its default: 1 step); return the Result."""
    request = StepSimulation.Request() if steps is None else StepSimulation.Request(steps=steps)
    return world.call(StepSimulation, '/step_simulation', request, timeout=timeout).result


def paused_parameter(world):
    return world.ros.get_parameter('mujoco', 'paused').bool_value


def position(world, name='tinybot'):
    response = world.state(name)
    assert response.success, response.status_message
    point = response.pose.position
    return np.array([point.x, point.y, point.z])


def sim_time(world):
    """Return the world's simulation time, read from the core."""
    return world.node.world.time


def wait_for_clock(world, expected):
    """Wait until /clock says expected (s)."""
    assert world.ros.wait_for(lambda: world.now() == pytest.approx(expected, abs=1e-9)), \
        f'/clock says {world.now()}, not {expected}'


@pytest.fixture
def paused_world(ros):
    """Start the default world (tinybot) paused, in real time when it plays."""
    return ros.start_world(paused=True)


class Goal:
    """One SimulateSteps goal, with the feedback that came for it."""

    def __init__(self, world, steps):
        self.ros = world.ros
        self.feedback = []  # (wall time, completed_steps, remaining_steps)
        client = self.ros.action_client(SimulateSteps, '/simulate_steps')
        assert client.wait_for_server(timeout_sec=10.0)
        future = client.send_goal_async(
            SimulateSteps.Goal(steps=steps), feedback_callback=lambda msg: self.feedback.append(
                (time.monotonic(), msg.feedback.completed_steps, msg.feedback.remaining_steps)))
        assert self.ros.wait_for(future.done), 'no answer to the goal'
        self.handle = future.result()
        assert self.handle.accepted
        self.result_future = self.handle.get_result_async()

    def result(self, timeout=60.0):
        """Return the goal's status and Result, waiting for them."""
        assert self.ros.wait_for(self.result_future.done, timeout=timeout)
        response = self.result_future.result()
        return response.status, response.result.result


# --- features ---------------------------------------------------------------------------------

def test_all_32_features_are_claimed(fast_world):
    features = fast_world.call(GetSimulatorFeatures, '/get_simulator_features',
                               GetSimulatorFeatures.Request()).features
    every = {value for name, value in vars(SimulatorFeatures).items()
             if name.isupper() and isinstance(value, int)}
    assert len(every) == 32
    assert list(features.features) == sorted(every)
    assert list(features.spawn_formats) == ['urdf', 'mjcf', 'sdf']
    assert 'MuJoCo' in features.custom_info


# --- states -----------------------------------------------------------------------------------

def test_the_world_starts_playing_and_time_runs(fast_world):
    assert state(fast_world) == PLAYING
    start = fast_world.now()
    fast_world.wait_sim(0.1)
    assert fast_world.now() > start


def test_the_paused_parameter_starts_it_paused(paused_world):
    assert state(paused_world) == PAUSED
    assert paused_world.node.world.time == 0.0


def test_the_lessons_pause_and_the_parameter_are_the_same_switch(fast_world):
    world = fast_world
    world.empty('pause_physics')
    assert state(world) == PAUSED
    world.empty('unpause_physics')
    assert state(world) == PLAYING
    assert set_state(world, PAUSED).result == OK
    assert paused_parameter(world) is True
    paused_at = sim_time(world)
    world.wait_ticks(5)
    assert sim_time(world) == paused_at
    assert world.ros.set_parameter('mujoco', 'paused', False).successful
    assert state(world) == PLAYING
    assert set_state(world, PLAYING).result == ALREADY


def test_every_transition_between_the_states_and_its_refusals(fast_world):
    world = fast_world
    # (target, the code of the answer, the state after it)
    walk = [(PLAYING, ALREADY, PLAYING), (PAUSED, OK, PAUSED), (PAUSED, ALREADY, PAUSED),
            (PLAYING, OK, PLAYING), (STOPPED, OK, STOPPED), (STOPPED, ALREADY, STOPPED),
            (PAUSED, OK, PAUSED), (STOPPED, OK, STOPPED), (PLAYING, OK, PLAYING)]
    for target, code, after in walk:
        result = set_state(world, target)
        assert (result.result, state(world)) == (code, after), \
            f'to {target}: {result.error_message}'
        assert paused_parameter(world) is (after != PLAYING)
    assert 'already PLAYING' in set_state(world, PLAYING).error_message


@pytest.mark.parametrize('target, code, named', [
    (SimulationState.STATE_LOADING_WORLD, INCORRECT, 'LOADING_WORLD'),
    (6, INCORRECT, 'state 6'), (7, INCORRECT, 'state 7'), (255, INCORRECT, 'state 255')])
def test_states_not_served_and_no_states_are_refused_and_change_nothing(
        fast_world, target, code, named):
    set_state(fast_world, PAUSED)
    time_before = sim_time(fast_world)
    result = set_state(fast_world, target)
    assert result.result == code
    assert named in result.error_message
    assert state(fast_world) == PAUSED and sim_time(fast_world) == time_before


def test_a_stop_pauses_and_resets_time_poses_and_spawned_entities(fast_world):
    world = fast_world
    world.spawn_or_fail('visitor', read_file(TINYBOT), make_pose(2.0, 0.0, 0.0),
                        namespace='visitor')
    assert world.set_state('tinybot', make_pose(1.0, 1.0, 0.0)).success
    world.wait_sim(0.2)
    assert set_state(world, STOPPED).result == OK
    assert state(world) == STOPPED and sim_time(world) == 0.0
    wait_for_clock(world, 0.0)
    assert world.models() == ['tinybot']
    np.testing.assert_allclose(position(world)[:2], [0.0, 0.0], atol=1e-9)
    # Stopped is paused: time stands still.
    world.wait_ticks(5)
    assert sim_time(world) == 0.0


def test_quitting_ends_the_world_program_with_status_0(ros, start_program):
    from programs import program_path
    # In a namespace of its own: no earlier world of this process answers in its place.
    process = start_program([program_path('mujoco_world'), '--ros-args', '-r', '__ns:=/quitter'])
    result = ros.call(SetSimulationState, '/quitter/set_simulation_state',
                      SetSimulationState.Request(state=SimulationState(state=QUITTING)),
                      timeout=60.0)
    assert result.result.result == OK, result.result.error_message
    assert process.wait(timeout=30) == 0, process.stderr.read()


def test_a_quitting_world_refuses_every_other_state(fast_world):
    assert set_state(fast_world, QUITTING).result == OK
    assert fast_world.node.quitting.done()
    assert state(fast_world) == QUITTING
    assert set_state(fast_world, QUITTING).result == ALREADY
    for target in (STOPPED, PLAYING, PAUSED):
        result = set_state(fast_world, target)
        assert result.result == INCORRECT and 'quitting' in result.error_message


# --- resets -----------------------------------------------------------------------------------

@pytest.mark.parametrize('scope, time_reset, poses_reset, spawned_gone', [
    (ResetSimulation.Request.SCOPE_TIME, True, False, False),
    (ResetSimulation.Request.SCOPE_STATE, False, True, False),
    (ResetSimulation.Request.SCOPE_SPAWNED, False, False, True),
    (3, True, True, False),
    (6, False, True, True),
    (ResetSimulation.Request.SCOPE_DEFAULT, True, True, True),
    (ResetSimulation.Request.SCOPE_ALL, True, True, True),
])
def test_each_reset_scope_resets_what_it_names_and_nothing_else(
        paused_world, scope, time_reset, poses_reset, spawned_gone):
    world = paused_world
    world.spawn_or_fail('visitor', read_file(TINYBOT), make_pose(2.0, 0.0, 0.0),
                        namespace='visitor')
    assert step(world, 100).result == OK
    assert world.set_state('tinybot', make_pose(1.0, 1.0, 0.0)).success
    assert world.set_state('visitor', make_pose(2.0, 2.0, 0.0)).success
    assert reset(world, scope).result == OK
    assert sim_time(world) == (0.0 if time_reset else pytest.approx(100 * TIMESTEP))
    wait_for_clock(world, sim_time(world))
    tinybot = [0.0, 0.0] if poses_reset else [1.0, 1.0]
    np.testing.assert_allclose(position(world)[:2], tinybot, atol=1e-6)
    if spawned_gone:
        assert world.models() == ['tinybot']
    else:
        visitor = [2.0, 0.0] if poses_reset else [2.0, 2.0]
        np.testing.assert_allclose(position(world, 'visitor')[:2], visitor, atol=1e-6)
    assert state(world) == PAUSED  # a reset changes no state


def test_a_start_up_model_spawned_again_counts_as_spawned(paused_world):
    world = paused_world
    assert world.delete('tinybot').success
    world.spawn_or_fail('tinybot', read_file(TINYBOT))
    assert reset(world, ResetSimulation.Request.SCOPE_SPAWNED).result == OK
    assert world.models() == []


@pytest.mark.parametrize('scope', [8, 16, 9, 128, 254])
def test_scopes_with_bits_the_standard_does_not_define_are_refused(paused_world, scope):
    world = paused_world
    world.spawn_or_fail('visitor', read_file(TINYBOT), make_pose(2.0, 0.0, 0.0),
                        namespace='visitor')
    assert step(world, 10).result == OK
    result = reset(world, scope)
    assert result.result == Result.RESULT_FEATURE_UNSUPPORTED
    assert f'scope {scope}' in result.error_message
    assert world.models() == ['tinybot', 'visitor']
    assert sim_time(world) == pytest.approx(10 * TIMESTEP)


def test_the_lessons_reset_and_the_standards_both_serve(fast_world):
    world = fast_world
    world.wait_sim(0.1)
    world.empty('reset_simulation')
    assert reset(world, ResetSimulation.Request.SCOPE_DEFAULT).result == OK
    assert state(world) == PLAYING


# --- stepping ---------------------------------------------------------------------------------

@pytest.mark.parametrize('real_time_factor', [1.0, 0.0])
def test_steps_are_exact_and_leave_the_world_paused(ros, real_time_factor):
    world = ros.start_world(paused=True, real_time_factor=real_time_factor)
    for steps, total in [(1, 1), (1, 2), (499, 501), (1000, 1501)]:
        assert step(world, None if steps == 1 else steps).result == OK
        assert sim_time(world) == pytest.approx(total * TIMESTEP, abs=1e-12)
        wait_for_clock(world, total * TIMESTEP)
        assert state(world) == PAUSED
    world.wait_ticks(5)
    assert sim_time(world) == pytest.approx(1501 * TIMESTEP, abs=1e-12)


def test_a_driven_tinybot_moves_as_in_normal_stepping_with_its_odometry(paused_world):
    world = paused_world
    odometry = world.ros.subscribe(Odometry, '/odom')
    # 10 steps, until odometry (50 Hz: every 10 steps) reaches the test.
    assert world.ros.wait_for(lambda: step(world, 10).result == OK and odometry)
    before = len(odometry)
    cmd_vel = world.ros.client_node.create_publisher(Twist, '/cmd_vel', 10)
    assert world.ros.wait_for(lambda: cmd_vel.get_subscription_count() > 0)
    command = Twist()
    command.linear.x, command.angular.z = 0.3, 0.5
    cmd_vel.publish(command)
    # The world takes commands at its ticks, which go on while it is paused.
    drive = world.node.world.models['tinybot'].drive()
    assert world.ros.wait_for(lambda: drive.commanded_at is not None)
    commanded_at = drive.commanded_at
    steps = 400
    assert step(world, steps).result == OK
    end = sim_time(world)
    # The same in a world of the core, stepped as it runs: commanded after the first steps.
    reference = World()
    spawn_file(reference, 'tinybot', TINYBOT)
    reference.step(round(commanded_at / TIMESTEP))
    reference.models['tinybot'].drive().command_velocity(0.3, 0.5)
    reference.step(steps)
    assert reference.time == pytest.approx(end, abs=1e-12)
    np.testing.assert_allclose(position(world), reference.get_model_state('tinybot').position,
                               atol=1e-9)
    assert np.linalg.norm(position(world)[:2]) > 0.1
    # Odometry went out on the way, as free-running (held to 50 Hz of wall time too), and
    # where the steps ended.
    assert world.ros.wait_for(lambda: seconds_of(odometry[-1].header.stamp) == pytest.approx(
        end, abs=1e-9))
    stamps = np.array([seconds_of(message.header.stamp) for message in odometry[before:]])
    assert all(np.diff(stamps) > 0)
    np.testing.assert_allclose(stamps / TIMESTEP, np.round(stamps / TIMESTEP), atol=1e-6)


@pytest.mark.parametrize('steps, named', [(0, '0'), (LONGEST, str(LONGEST))])
def test_step_counts_of_0_and_too_many_are_refused_at_once(paused_world, steps, named):
    # At once: before a single step. A world that took the count on would not answer within
    # the call's timeout, and its time would have moved.
    result = step(paused_world, steps, timeout=5.0)
    assert result.result == FAILED and named in result.error_message
    assert sim_time(paused_world) == 0.0
    assert state(paused_world) == PAUSED


def test_stepping_a_playing_world_fails_and_says_it_is_not_paused(fast_world):
    result = step(fast_world, 10)
    assert result.result == FAILED and 'not paused' in result.error_message
    goal = Goal(fast_world, 10)
    status, result = goal.result()
    assert status == GoalStatus.STATUS_ABORTED
    assert result.result == FAILED and 'not paused' in result.error_message


def test_stepping_a_stopped_world_leaves_it_paused(fast_world):
    assert set_state(fast_world, STOPPED).result == OK
    assert step(fast_world, 10).result == OK
    assert state(fast_world) == PAUSED
    assert sim_time(fast_world) == pytest.approx(10 * TIMESTEP)


def test_the_action_reports_progress_ten_times_a_second_and_ends_exact(paused_world):
    world = paused_world
    steps = 40_000
    started = time.monotonic()
    goal = Goal(world, steps)
    status, result = goal.result()
    duration = time.monotonic() - started
    assert (status, result.result) == (GoalStatus.STATUS_SUCCEEDED, OK), result.error_message
    assert sim_time(world) == pytest.approx(steps * TIMESTEP, abs=1e-9)
    wait_for_clock(world, steps * TIMESTEP)
    assert state(world) == PAUSED
    assert world.ros.wait_for(lambda: goal.feedback and goal.feedback[-1][1] == steps)
    print(f'\n{steps} steps in {duration:.2f} s, {len(goal.feedback)} feedback messages')
    assert goal.feedback[-1][1:] == (steps, 0)
    completed = [taken for _, taken, _ in goal.feedback]
    assert completed == sorted(completed)
    assert all(taken + remaining == steps for _, taken, remaining in goal.feedback)
    assert 2 <= len(goal.feedback) <= 10 * duration + 2


def test_a_long_action_lets_other_services_answer_and_stops_on_cancel(paused_world):
    world = paused_world
    goal = Goal(world, LONGEST)
    assert world.ros.wait_for(lambda: goal.feedback), 'no feedback'
    stepped_before = goal.feedback[-1][1]
    for _ in range(5):
        assert world.models() == ['tinybot']
        assert state(world) == PAUSED
        # Answered while the action was stepping, not after it: it has no end. How soon is
        # the benchmark's (its standard section: get_model_list while StepSimulation steps).
        assert not goal.result_future.done()
    # The action went on stepping between the answers.
    assert world.ros.wait_for(lambda: goal.feedback[-1][1] > stepped_before)
    assert step(world, 10).result == Result.RESULT_INCORRECT_STATE  # one stepping at a time
    cancel = goal.handle.cancel_goal_async()
    assert world.ros.wait_for(cancel.done)
    status, result = goal.result()
    assert status == GoalStatus.STATUS_CANCELED
    assert result.result == FAILED and 'cancelled after' in result.error_message
    taken = int(result.error_message.split('cancelled after ')[1].split()[0])
    assert taken > 0
    assert sim_time(world) == pytest.approx(taken * TIMESTEP, rel=1e-9)
    assert world.ros.wait_for(lambda: goal.feedback[-1][1:] == (taken, LONGEST - taken))
    assert state(world) == PAUSED


@pytest.mark.parametrize('play', ['set_simulation_state', 'unpause_physics'])
def test_playing_ends_a_stepping_early_and_says_after_how_many_steps(paused_world, play):
    world = paused_world
    goal = Goal(world, LONGEST)
    assert world.ros.wait_for(lambda: goal.feedback), 'no feedback'
    if play == 'unpause_physics':
        world.empty('unpause_physics')
    else:
        assert set_state(world, PLAYING).result == OK
    status, result = goal.result()
    assert status == GoalStatus.STATUS_ABORTED
    assert result.result == FAILED and 'set playing after' in result.error_message
    assert state(world) == PLAYING


def test_the_action_refuses_0_steps(paused_world):
    status, result = Goal(paused_world, 0).result()
    assert status == GoalStatus.STATUS_ABORTED
    assert result.result == FAILED and 'at least 1: 0' in result.error_message


def test_a_stop_ends_a_stepping_and_puts_time_back_to_zero(paused_world):
    world = paused_world
    goal = Goal(world, LONGEST)
    assert world.ros.wait_for(lambda: goal.feedback), 'no feedback'
    assert set_state(world, STOPPED).result == OK
    status, result = goal.result()
    assert status == GoalStatus.STATUS_ABORTED and 'stopped after' in result.error_message
    assert sim_time(world) == 0.0 and state(world) == STOPPED
    world.wait_ticks(5)
    assert sim_time(world) == 0.0
    assert math.isclose(world.now(), 0.0, abs_tol=1e-12)
