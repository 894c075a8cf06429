"""The turning server through /control_robot_angle, turning tinybot in a world the test steps."""

import math

from geometry_msgs.msg import Twist
import pytest
from rcl_interfaces.srv import GetParameters
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.time import Time
from rosgraph_msgs.msg import Clock
from service_tutorial.conversions import yaw_of
from service_tutorial.lesson.robot_turning_server import RobotTurningServer
from service_tutorial.testing.simulated_world import SimulatedWorld
from simulation_interfaces.srv import ResetSimulation
from srv_interfaces.srv import ControlTurningMessage
from std_srvs.srv import Empty

pytestmark = pytest.mark.ros
# Steps taken at a time, 20 ms: a stop lands at the first step after the turn's end, so a turn
# lasts up to this much longer than asked.
CHUNK = 10
# The most simulation time a test waits for tinybot to do what it should, in s.
TURN_LIMIT = 30.0


def turning_request(time_duration, angular_vel):
    return ControlTurningMessage.Request(time_duration=time_duration, angular_vel=angular_vel)


class TurningWorld:
    """A paused world, the turning server on its simulation time and a client; the test steps."""

    def __init__(self):
        self.world = SimulatedWorld()
        try:
            context = self.world.context
            self.server = self.world.add_node(RobotTurningServer(
                context=context, parameter_overrides=[Parameter('use_sim_time', value=True)]))
            user = self.world.add_node(Node('turning_test', context=context))
            self.cmd_vel = []
            user.create_subscription(Twist, '/cmd_vel', self.cmd_vel.append, 100)
            self.turning_cli = user.create_client(ControlTurningMessage, '/control_robot_angle')
            assert self.turning_cli.wait_for_service(timeout_sec=10.0)
        except BaseException:
            self.world.close()
            raise

    def close(self):
        self.world.close()

    def heading(self):
        """Tinybot's heading in the world, from its ground truth."""
        return yaw_of(self.state().pose.orientation)

    def state(self):
        return self.world.entity_state('tinybot')

    def step_until(self, predicate, *, limit=TURN_LIMIT):
        """Step CHUNK steps at a time until predicate(); return False past limit s."""
        end = self.world.time + limit
        while not predicate():
            if self.world.time >= end:
                return False
            self.world.step(CHUNK)
        return True

    def step_for(self, seconds):
        self.world.step(round(seconds / self.world.timestep))

    def heading_at_rest(self):
        """Tinybot's heading once it has stopped turning."""
        assert self.step_until(lambda: abs(self.state().twist.angular.z) < 1e-3)
        return self.heading()

    def turn_async(self, time_duration, angular_vel):
        return self.turning_cli.call_async(turning_request(time_duration, angular_vel))

    def turn(self, time_duration, angular_vel):
        """Ask for a turn; return the answer and how far tinybot turned (|turn| < pi)."""
        before = self.heading_at_rest()
        future = self.turn_async(time_duration, angular_vel)
        assert self.step_until(future.done, limit=time_duration + 5.0)
        turned = math.remainder(self.heading_at_rest() - before, math.tau)
        return future.result(), turned

    def commands(self):
        """Angular velocities published on /cmd_vel so far."""
        return [msg.angular.z for msg in self.cmd_vel]


@pytest.fixture
def turning_world():
    stepped = TurningWorld()
    yield stepped
    stepped.close()


def test_two_seconds_at_half_a_radian_per_second_turn_tinybot_one_radian(turning_world):
    response, turned = turning_world.turn(2, 0.5)

    assert response.success
    assert turned == pytest.approx(1.0, rel=0.03)
    assert turning_world.world.wait_for(lambda: turning_world.cmd_vel[-1] == Twist())
    # 20 Hz of simulation time for 2 s, then one zero Twist.
    commands = turning_world.commands()
    assert commands[-1] == 0.0
    assert 38 <= commands.count(0.5) <= 42


def clock_teller(ros, server):
    """Return tell_time(seconds): publish /clock until the server's clock shows it."""
    clock = ros.client_node.create_publisher(Clock, '/clock', 10)

    def tell_time(seconds):
        nanoseconds = round(seconds * 1e9)

        def heard():  # said again until heard: /clock is best effort
            clock.publish(Clock(clock=Time(nanoseconds=nanoseconds).to_msg()))
            return server.get_clock().now().nanoseconds == nanoseconds
        assert ros.wait_for(heard), f'the server did not hear /clock {seconds}'
    return tell_time


def test_on_simulation_time_a_turn_counts_from_the_clock_message_that_started_it(ros, capfd):
    # A world takes commands at its ticks and says the time after stepping. The stop goes out
    # right after a /clock message; the start must too, or a start sent on the time of the
    # last message can reach the world after its next steps began, and the turn comes short.
    server = ros.add_node(RobotTurningServer(
        parameter_overrides=[Parameter('use_sim_time', value=True)]))
    tell_time = clock_teller(ros, server)
    cmd_vel = ros.subscribe(Twist, '/cmd_vel')
    turning_cli = ros.client_node.create_client(ControlTurningMessage, '/control_robot_angle')
    assert turning_cli.wait_for_service(timeout_sec=10.0)
    assert ros.wait_for(lambda: server.cmd_vel_pub.get_subscription_count() > 0)

    tell_time(5.0)
    answer = turning_cli.call_async(turning_request(1, 0.5))
    assert ros.wait_for(lambda: server.turns), 'the request was not queued'
    assert server.turns[0].start is None
    tell_time(5.25)
    assert ros.wait_for(lambda: 0.5 in [msg.angular.z for msg in cmd_vel])
    tell_time(6.2)
    tell_time(6.25)

    assert ros.wait_for(answer.done)
    assert answer.result().success
    assert ros.wait_for(lambda: cmd_vel[-1] == Twist())
    log = capfd.readouterr().err
    assert 'Done ... after 1.000 s' in log, log


def test_on_simulation_time_a_turn_waits_a_second_for_a_cmd_vel_listener(ros):
    server = ros.add_node(RobotTurningServer(
        parameter_overrides=[Parameter('use_sim_time', value=True)]))
    tell_time = clock_teller(ros, server)
    turning_cli = ros.client_node.create_client(ControlTurningMessage, '/control_robot_angle')
    assert turning_cli.wait_for_service(timeout_sec=10.0)
    tell_time(1.0)
    answer = turning_cli.call_async(turning_request(1, 0.5))
    assert ros.wait_for(lambda: server.turns), 'the request was not queued'

    # /clock at 250 Hz for 0.4 s, and nobody on cmd_vel: the command would be lost.
    for tick in range(1, 101):
        tell_time(1.0 + 0.004 * tick)
    assert server.turns[0].start is None, 'the turn began with nobody listening'
    cmd_vel = ros.subscribe(Twist, '/cmd_vel')
    assert ros.wait_for(lambda: server.cmd_vel_pub.get_subscription_count() > 0)
    tell_time(1.45)
    tell_time(1.5)  # the publish timer's next tick, 50 ms of simulation time apart

    assert ros.wait_for(lambda: 0.5 in [msg.angular.z for msg in cmd_vel])
    tell_time(2.5)
    assert ros.wait_for(answer.done) and answer.result().success


@pytest.mark.parametrize('time_duration, angular_vel', [(1, 0.1), (1, 1.5), (5, -0.5)])
def test_turning_error_stays_under_two_percent_and_a_tick(turning_world, time_duration,
                                                          angular_vel):
    response, turned = turning_world.turn(time_duration, angular_vel)

    assert response.success
    # The stop lands at the first step after the turn's end: up to a chunk of steps late.
    late = abs(angular_vel) * CHUNK * turning_world.world.timestep
    assert turned == pytest.approx(time_duration * angular_vel,
                                   abs=0.02 * abs(time_duration * angular_vel) + late)


def test_server_keeps_serving_during_a_turn_and_queues_the_next(turning_world):
    world, server = turning_world.world, turning_world.server
    before = turning_world.heading_at_rest()
    answered = []
    first = turning_world.turn_async(2, 0.6)
    first.add_done_callback(lambda _: answered.append('first'))
    assert turning_world.step_until(lambda: 0.6 in turning_world.commands())
    second = turning_world.turn_async(1, 0.4)
    second.add_done_callback(lambda _: answered.append('second'))

    # The server's own parameter service answers and its clock follows /clock mid-turn.
    parameters = world.call(GetParameters, '/robot_turning_server/get_parameters',
                            GetParameters.Request(names=['max_angular_vel']))
    assert parameters.values[0].double_value == pytest.approx(1.5707)
    start = server.get_clock().now().nanoseconds
    assert turning_world.step_until(
        lambda: server.get_clock().now().nanoseconds > start + 500_000_000)
    assert not first.done()

    assert turning_world.step_until(first.done, limit=10.0)
    after_first = turning_world.heading()
    assert turning_world.step_until(second.done, limit=10.0)
    after_both = turning_world.heading_at_rest()

    assert answered == ['first', 'second']
    assert first.result().success and second.result().success
    assert after_first - before == pytest.approx(1.2, rel=0.05)
    assert after_both - before == pytest.approx(1.6, rel=0.03)
    # One turn after the other, each ended by its own stop.
    commands = turning_world.commands()
    changes = [z for i, z in enumerate(commands) if i == 0 or z != commands[i - 1]]
    assert changes == [0.6, 0.0, 0.4, 0.0]


@pytest.mark.parametrize('request_fields', [
    {'time_duration': 2, 'angular_vel': 2.0},
    {'time_duration': 2, 'angular_vel': -2.0},
    {'time_duration': 2, 'angular_vel': math.nan},
    {'time_duration': 2, 'angular_vel': math.inf},
    {'time_duration': 61, 'angular_vel': 0.5},
], ids=['too-fast', 'too-fast-right', 'nan', 'infinite', 'too-long'])
def test_invalid_requests_are_refused_and_tinybot_stays_still(turning_world, request_fields):
    before = turning_world.heading_at_rest()

    response = turning_world.world.call(ControlTurningMessage, '/control_robot_angle',
                                        ControlTurningMessage.Request(**request_fields))

    assert not response.success
    assert turning_world.commands() == []
    assert turning_world.heading_at_rest() == pytest.approx(before, abs=1e-4)


def test_a_zero_second_turn_stops_tinybot_and_succeeds(turning_world):
    before = turning_world.heading_at_rest()

    response = turning_world.world.call(ControlTurningMessage, '/control_robot_angle',
                                        turning_request(0, 1.0))

    assert response.success
    assert turning_world.world.wait_for(lambda: turning_world.commands() == [0.0])
    assert turning_world.heading_at_rest() == pytest.approx(before, abs=1e-4)


def lesson_reset(world):
    """Reset the simulation the lesson's way: time to 0, every model at its spawn pose."""
    world.call(Empty, '/mujoco/reset_simulation', Empty.Request())
    assert world.wait_for(lambda: world.time == 0.0), '/clock did not go back to 0'


def standard_time_reset(world):
    """Put only time back through the standard /reset_simulation; models stay where they are."""
    world.reset(ResetSimulation.Request.SCOPE_TIME)


def reset_during_a_long_turn(turning_world, *queued, reset=lesson_reset):
    """Start a 10 s turn (and queue more), reset the simulation 1 s in; return the futures."""
    world = turning_world.world
    turning_world.heading_at_rest()
    long_turn = turning_world.turn_async(10, 0.5)
    assert turning_world.step_until(lambda: 0.5 in turning_world.commands())
    more = [turning_world.turn_async(*turn) for turn in queued]
    turning_world.step_for(1.0)
    assert not long_turn.done()
    reset(world)
    # At once: without a step after the world's answer to the reset.
    assert world.wait_for(long_turn.done), 'no answer before the next step'
    return long_turn, more


@pytest.mark.parametrize('reset', [lesson_reset, standard_time_reset],
                         ids=['mujoco-reset_simulation', 'standard-reset-of-time'])
def test_a_reset_during_a_turn_ends_it_at_once_stops_tinybot_and_turning_goes_on(
        turning_world, capfd, reset):
    long_turn, _ = reset_during_a_long_turn(turning_world, reset=reset)

    assert not long_turn.result().success
    assert turning_world.world.wait_for(lambda: turning_world.cmd_vel[-1] == Twist())
    told_to_stop = len(turning_world.cmd_vel)
    turning_world.step_for(0.5)
    assert abs(turning_world.state().twist.angular.z) < 1e-3
    assert turning_world.commands()[told_to_stop - 1:] == [0.0]  # nothing sent after the stop
    log = capfd.readouterr().err
    assert 'simulation time jumped back by' in log, log
    assert '(the simulation was reset): turn of 0.5 rad/s for 10 s ended after' in log, log
    response, turned = turning_world.turn(1, 0.5)
    assert response.success
    assert turned == pytest.approx(0.5, abs=0.01 + 0.5 * CHUNK * turning_world.world.timestep)


def test_turns_queued_behind_a_turn_a_reset_ended_are_carried_out(turning_world):
    before = turning_world.heading()  # the spawn heading, where the reset puts tinybot back

    long_turn, (queued,) = reset_during_a_long_turn(turning_world, (1, -0.5))

    assert not long_turn.result().success
    assert turning_world.step_until(queued.done, limit=10.0)
    assert queued.result().success
    turned = math.remainder(turning_world.heading_at_rest() - before, math.tau)
    assert turned == pytest.approx(-0.5, abs=0.01 + 0.5 * CHUNK * turning_world.world.timestep)
    commands = turning_world.commands()
    changes = [z for i, z in enumerate(commands) if i == 0 or z != commands[i - 1]]
    assert changes == [0.5, 0.0, -0.5, 0.0]
