"""The world node's pacing scheduler, driven by fake wall and CPU clocks: no ROS, no physics."""

import math

import pytest
from service_tutorial.world_node import pacing
from service_tutorial.world_node.pacing import Pacer

TIMESTEP = 0.002
RATES = {'clock': 250.0, 'odom': 50.0}  # Hz of simulation time: every 2 and every 10 steps
ODOMETRY_STEPS = 10


class FakeClock:
    """A clock that stands still until a test moves it."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


class FakeWorld:
    """Counts steps like a world, costs wall time per step, and records what was published."""

    def __init__(self, pacer, wall, step_cost=0.0, chunk_cost=0.0):
        self.pacer = pacer
        self.wall = wall
        self.step_cost = step_cost
        self.chunk_cost = chunk_cost  # besides its steps: publishing, Python
        self.steps = 0
        self.chunks = []
        self.published = {name: [] for name in RATES}
        self.stamps = {name: [] for name in RATES}
        self.other_due = math.inf

    @property
    def time(self):
        return self.steps * TIMESTEP

    def tick(self):
        """Do what the node's step callback does: step chunk by chunk, publish what is due."""
        for steps in self.pacer.chunks(lambda: self.time, lambda: self.other_due):
            self.steps += steps
            self.wall.now += steps * self.step_cost + self.chunk_cost
            self.chunks.append(steps)
            self.publish_due()
        self.publish_due()

    def publish_due(self):
        for name, stamp in self.pacer.take_due(self.time):
            self.published[name].append(self.steps)
            self.stamps[name].append(round(stamp / TIMESTEP))


def at_last_turn_before(world, steps):
    """Tell whether a world in real time stands at the last odometry turn by steps (or one on)."""
    return -1 <= steps - world.steps < ODOMETRY_STEPS and world.steps in world.published['odom']


def make(real_time_factor, step_cost=0.0, chunk_cost=0.0):
    """Return a pacer on fake clocks and a fake world it paces, anchored at time 0."""
    wall, cpu = FakeClock(), FakeClock()
    pacer = Pacer(timestep=TIMESTEP, real_time_factor=real_time_factor,
                  periods={name: 1.0 / rate for name, rate in RATES.items()},
                  wall_clock=wall, cpu_clock=cpu)
    world = FakeWorld(pacer, wall, step_cost, chunk_cost)
    pacer.anchor(world.time)
    return pacer, world, wall, cpu


def test_real_time_steps_as_far_as_the_wall_clock_went_and_publishes_at_the_rates():
    pacer, world, wall, _ = make(1.0)
    world.tick()
    assert world.steps == 0 and world.published == {'clock': [0], 'odom': [0]}
    wall.now += 0.1
    world.tick()
    assert world.steps == 50
    # The chunks end where odometry falls due, which needs the world's state at its step.
    assert world.chunks == [10] * 5
    assert world.published['odom'] == world.stamps['odom'] == [0, 10, 20, 30, 40, 50]
    # /clock only tells the time: its turns go out after each chunk, stamped with their step.
    assert world.stamps['clock'] == list(range(0, 51, 2))
    assert world.published['clock'] == [0] + [10 * (1 + i // 5) for i in range(25)]


def test_clock_turns_a_chunk_passed_go_out_in_order_one_per_step_at_most():
    pacer, world, wall, _ = make(1.0)
    world.tick()
    pacer.set_period('clock', 0.003)  # every step and a half
    wall.now += 0.06
    world.tick()
    stamps = world.stamps['clock'][1:]
    assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps)
    assert {b - a for a, b in zip(stamps, stamps[1:])} == {1, 2}
    assert len(stamps) == pytest.approx(0.06 / 0.003, abs=1)
    pacer.set_period('clock', 0.0001)  # far shorter than a step: once per step
    wall.now += 0.02
    world.tick()
    assert world.stamps['clock'][-10:] == list(range(world.steps - 9, world.steps + 1))


def test_real_time_factor_two_runs_twice_as_fast():
    pacer, world, wall, _ = make(2.0)
    for _ in range(5):
        wall.now += 0.02
        world.tick()
    assert at_last_turn_before(world, 100)


def test_real_time_ticks_end_where_odometry_falls_due_however_the_wall_clock_jitters():
    pacer, world, wall, _ = make(1.0)
    world.tick()
    ends = []
    for jitter in (0.0, 0.001, -0.0015, 0.0007, 0.0, -0.0009, 0.0012, 0.0, -0.0004, 0.0):
        wall.now += 0.02 + jitter
        before = len(world.chunks)
        world.tick()
        ends.append(world.steps)
        # One chunk a tick: it ends where odometry falls due, and nothing is stepped past it.
        assert world.chunks[before:] == [ODOMETRY_STEPS]
        assert at_last_turn_before(world, round(wall.now / TIMESTEP))
    assert ends == list(range(10, 101, 10))


def test_real_time_steps_on_past_a_turn_rather_than_leave_more_than_a_tick_for_the_next():
    wall, cpu = FakeClock(), FakeClock()
    pacer = Pacer(timestep=TIMESTEP, real_time_factor=1.0, periods={'odom': 1.0},
                  wall_clock=wall, cpu_clock=cpu)
    world = FakeWorld(pacer, wall)
    pacer.anchor(world.time)
    world.tick()
    for _ in range(49):  # no turn within these ticks: each steps as far as the wall clock went
        wall.now += 0.02
        world.tick()
    assert world.steps == 490
    wall.now += 0.05
    world.tick()
    # The turn at 1 s is 10 steps in; ending the tick there would leave 30 ms for the next.
    assert world.steps == 515 and 500 in world.published['odom']


def test_real_time_counts_from_the_first_tick_not_from_when_the_pacer_was_made():
    wall = FakeClock()
    pacer = Pacer(timestep=TIMESTEP, real_time_factor=1.0, periods={}, wall_clock=wall,
                  cpu_clock=FakeClock())
    world = FakeWorld(pacer, wall, 0.0, 0.0)
    wall.now += 0.2  # the node took this long to start spinning
    world.tick()
    assert world.steps == 0
    wall.now += 0.01
    world.tick()
    assert world.steps == 5


def test_real_time_does_not_catch_up_more_than_a_tenth_of_a_second():
    pacer, world, wall, _ = make(1.0)
    wall.now += 0.5  # the machine stalled
    world.tick()
    assert at_last_turn_before(world, round(pacing.MAX_LAG / TIMESTEP))
    # From here on, real time counts from the end of the stall, not from before it.
    wall.now += 0.01
    world.tick()
    assert at_last_turn_before(world, 50 + 5)


def test_slow_steps_in_real_time_end_a_tick_after_its_budget_so_calls_come_in_between():
    # 20 ms a step (lasers cast at every step): real time cannot be kept.
    pacer, world, wall, _ = make(1.0, step_cost=0.02)
    wall.now += 0.1  # 50 steps fall due
    world.tick()  # the pacer learns what a step costs
    for _ in range(3):
        start = wall.now
        world.tick()
        # Knowing it, a tick ends within a step of its budget.
        assert wall.now - start <= pacing.MAX_STEP_BUDGET + 0.02 + 1e-9
        assert world.chunks[-1] <= 3
    assert pacer.step_wall_time == pytest.approx(0.02, rel=0.05)
    assert world.time < wall.now
    # Cheap steps again: the world catches up with real time as before, a tenth of a second
    # behind at most.
    world.step_cost = 0.0
    wall.now += 0.01
    world.tick()
    assert at_last_turn_before(
        world, round((pacer._sim_anchor + wall.now - pacer._wall_anchor) / TIMESTEP))


def test_time_the_world_was_held_is_not_made_up_but_steps_due_before_are_taken():
    pacer, world, wall, _ = make(1.0)
    wall.now += 0.004  # two steps fall due
    busy_since = wall.now
    wall.now += 0.010  # then a spawn keeps the world busy for 10 ms
    pacer.hold(busy_since)
    world.tick()
    assert world.steps == 2
    wall.now += 0.02
    world.tick()
    assert at_last_turn_before(world, 2 + 10)


def test_a_spawn_puts_the_next_tick_off_unless_ticks_were_already_put_off_too_long():
    pacer, _, wall, _ = make(1.0)
    pacer.start_tick()
    wall.now += 0.005
    assert pacer.hold(wall.now - 0.001)  # a call soon after a tick: the next may wait
    wall.now += pacing.MAX_DEFERRAL
    # Calls back to back since that tick: the next tick comes now.
    assert not pacer.hold(wall.now - 0.001)
    pacer.start_tick()
    assert pacer.hold(wall.now)


def test_stepping_also_stops_where_something_else_falls_due():
    pacer, world, wall, _ = make(1.0)
    world.tick()
    pacer.published('clock', 0.0)
    world.other_due = 0.011  # the camera: 5.5 steps away, due at step 6 with half a step slack
    wall.now += 0.02
    world.tick()
    assert world.chunks[0] == 5, 'the chunk ends at step 5, the camera within reach'
    # Free-running too, where /clock is held back by wall time and does not end the chunks.
    pacer, world, wall, _ = make(0.0, step_cost=1e-5)
    world.other_due = 0.1
    world.tick()
    assert 50 in [sum(world.chunks[:i]) for i in range(len(world.chunks))]


def test_free_running_steps_for_its_budget_and_holds_streams_to_their_wall_rate():
    pacer, world, wall, _ = make(0.0, step_cost=1e-5)
    start = wall.now
    world.tick()
    # 5 ms of stepping at 10 us a step: 500 steps, a whole second of simulation time.
    assert wall.now - start == pytest.approx(pacing.STEP_BUDGET, abs=1e-4)
    assert world.steps == pytest.approx(500, abs=10)
    # In simulation time /clock would have gone out 250 times; in 5 ms of wall time it goes
    # out twice, odometry once (every 20 ms). The first chunk is one step: every stream was
    # due at once. /clock only tells the time: it does not end a chunk, but goes out after
    # the first chunk past its turn (every 4 ms), here the tick's last.
    assert world.published['clock'] == [1, 500] and world.published['odom'] == [1]
    assert world.chunks == [1, 499]


def test_free_running_chunks_end_at_a_turn_however_much_a_chunk_costs_besides_its_steps():
    # A chunk that costs a step more than its steps (publishing, Python) does not make the
    # chunks shrink before each turn: a tick of 5 ms steps to odometry's turn (every 20 ms)
    # or its deadline, in one chunk each.
    pacer, world, wall, _ = make(0.0, step_cost=1e-4, chunk_cost=1e-4)
    for _ in range(10):
        world.tick()
    chunks = len(world.chunks)
    for _ in range(40):  # 200 ms: 40 deadlines and 10 turns of odometry
        world.tick()
    assert len(world.chunks) - chunks <= 55
    assert len(world.published['odom']) == pytest.approx(wall.now / 0.02, abs=2)


def test_free_running_learns_what_a_step_costs():
    pacer, world, wall, _ = make(0.0, step_cost=4e-5)
    for _ in range(5):
        world.tick()
    assert pacer.step_wall_time == pytest.approx(4e-5, rel=0.05)
    # Knowing it, one tick takes about its budget and no more.
    start = wall.now
    world.tick()
    assert wall.now - start == pytest.approx(pacing.STEP_BUDGET, rel=0.1)


def test_tick_periods_follow_the_executor_turn():
    pacer, world, wall, cpu = make(1.0)
    assert pacer.first_tick_period == pacing.REAL_TIME_PERIOD
    assert pacer.tick_period_ns(paused=False) == 2_000_000
    assert pacer.tick_period_ns(paused=True) == 20_000_000

    def turn(seconds):
        """One tick, then an executor turn of this many CPU seconds, then the next tick."""
        pacer.start_tick()
        pacer.end_tick()
        cpu.now += seconds
        pacer.start_tick()
    for _ in range(200):
        turn(0.00025)  # 0.25 ms between ticks: ticks every 60 turns, 15 ms
    assert pacer.executor_turn == pytest.approx(0.00025)
    assert pacer.tick_period_ns(paused=False) == 15_000_000
    turn(0.5)  # a slow service call is not overhead: the estimate barely moves
    assert pacer.executor_turn < 0.0003
    for _ in range(200):
        turn(0.003)  # 60 turns would be 180 ms
    assert pacer.tick_period_ns(paused=False) == 20_000_000, 'at most 20 ms'
    # Five times real time, a tick steps no more than 20 ms of simulated time either.
    pacer.set_real_time_factor(5.0, world.time)
    assert pacer.tick_period_ns(paused=False) == 4_000_000
    # Far faster, the period stays REAL_TIME_PERIOD rather than 0, which would spin.
    pacer.set_real_time_factor(100.0, world.time)
    assert pacer.tick_period_ns(paused=False) == 2_000_000

    free, *_ = make(0.0)
    assert free.first_tick_period == 0.0 and free.tick_period_ns(paused=False) == 0
    assert free.tick_period_ns(paused=True) == 20_000_000


def test_a_stream_is_due_within_half_a_step_and_after_a_reset_at_once():
    pacer, world, wall, _ = make(1.0)
    assert pacer.take_due(0.0) == [('clock', 0.0), ('odom', 0.0)]
    assert pacer.take_due(0.0) == []
    # Three steps of 0.002 s add up to a little less than 0.006: still the same step.
    assert 3 * TIMESTEP < 0.006 + 1e-12
    pacer.published('clock', 0.002)
    now = 0.002 + 0.002 + 0.002 - 1e-9
    assert pacer.take_due(now) == [('clock', now)]
    pacer.take_due(1.0)
    assert pacer.take_due(0.0) == [], 'simulation time went back; nothing is due'
    pacer.restart(0.0, ['odom'])
    assert pacer.take_due(0.0) == [('odom', 0.0)]


def test_with_nothing_due_a_chunk_takes_every_step_it_may():
    pacer = Pacer(timestep=TIMESTEP, real_time_factor=1.0, periods={})
    assert pacer.steps_to_next_due(0.0, limit=7) == 7
    assert pacer.take_due(0.0) == []


def test_a_new_real_time_factor_sets_the_pace_from_now_on():
    pacer, world, wall, _ = make(1.0)
    wall.now += 0.1
    world.tick()
    assert at_last_turn_before(world, 50)
    pacer.set_real_time_factor(2.0, world.time)
    wall.now += 0.04
    world.tick()
    assert at_last_turn_before(world, 50 + 40), 'twice as fast, from the change, not from start'
    pacer.set_real_time_factor(0.0, world.time)
    assert pacer.free_running and pacer.tick_period_ns(paused=False) == 0
    world.step_cost = 1e-5
    world.tick()
    assert world.steps > 90 + 400, 'free-running: a whole budget of steps in one tick'
    pacer.set_real_time_factor(1.0, world.time)
    steps = world.steps
    wall.now += 0.02
    world.tick()
    # Back in real time, /clock every 2 steps.
    assert at_last_turn_before(world, steps + 10)
    clocks = len([step for step in world.published['clock'] if step > steps])
    assert clocks == (world.steps - steps) // 2


def test_a_new_period_moves_the_next_turn_by_the_difference():
    pacer, world, wall, _ = make(1.0)
    world.tick()
    assert world.published['odom'] == [0]
    pacer.set_period('odom', 0.004)  # from every 10 steps to every 2
    wall.now += 0.01
    world.tick()
    assert world.published['odom'] == [0, 2, 4]
    pacer.set_period('odom', 0.1)
    wall.now += 0.1
    world.tick()
    assert world.published['odom'] == [0, 2, 4, 54]


def test_a_paused_world_says_its_time_again_every_paused_clock_period():
    pacer, world, wall, _ = make(1.0)
    assert pacer.repeat_due() and not pacer.repeat_due()
    wall.now += pacing.PAUSED_CLOCK_PERIOD - 0.001
    assert not pacer.repeat_due()
    wall.now += 0.001
    assert pacer.repeat_due()


@pytest.mark.parametrize('real_time_factor', [0.0, 1.0])
def test_steps_on_request_go_free_running_and_stop_at_the_count(real_time_factor):
    pacer, world, wall, _ = make(real_time_factor, step_cost=1e-5)

    def requested_tick(count):
        before = world.steps
        pacer.step_on_request(True)
        for steps in pacer.requested_chunks(count, lambda: world.time):
            world.steps += steps
            wall.now += steps * world.step_cost
            world.publish_due()
        pacer.step_on_request(False)
        return world.steps - before
    # 5 ms of wall time at 10 us a step, whatever the real-time factor: 500 of 10**6 steps,
    # with streams held to their rates in wall time, as free-running.
    assert requested_tick(10 ** 6) == pytest.approx(500, abs=10)
    assert world.published['clock'] == [1, 500] and world.published['odom'] == [1]
    assert requested_tick(2 ** 64 - 1) == pytest.approx(500, abs=10)
    before = world.steps
    assert requested_tick(7) == 7 and world.steps == before + 7
    # Done, the pace is the real-time factor's again.
    assert pacer.free_running is (real_time_factor == 0.0)


def test_a_tick_far_past_its_budget_is_followed_by_as_long_a_rest_for_the_calls_waiting():
    # 120 ms a step: a tick takes one step, far past its 50 ms budget.
    pacer, world, wall, _ = make(0.0, step_cost=0.12)
    pacer.start_tick()
    world.tick()
    pacer.end_tick()
    assert world.steps == 1
    assert pacer.resting()
    wall.now += 0.119
    assert pacer.resting()
    wall.now += 0.002
    assert not pacer.resting()
    # 70 ms a step: a little past its budget, the tick rests only as long as it ran over.
    world.step_cost = 0.07
    pacer.start_tick()
    world.tick()
    pacer.end_tick()
    wall.now += 0.019
    assert pacer.resting()
    wall.now += 0.002
    assert not pacer.resting()
    # A tick within its budget is not followed by a rest.
    world.step_cost = 0.001
    pacer.start_tick()
    world.tick()
    pacer.end_tick()
    assert world.steps > 1 and not pacer.resting()
    # However long a tick, the rest lasts MAX_REST at most.
    world.step_cost = 1.0
    pacer.start_tick()
    world.tick()
    pacer.end_tick()
    wall.now += pacing.MAX_REST + 1e-6
    assert not pacer.resting()


def test_after_a_tick_back_to_back_the_next_turn_goes_to_the_calls_waiting():
    pacer, world, _, _ = make(0.0, step_cost=0.001)
    pacer.start_tick()
    world.tick()
    pacer.end_tick(back_to_back=True)
    # The executor's next turn answers the calls that came during the tick; the one after ticks.
    assert pacer.resting()
    assert not pacer.resting()
    # A timer with a period gives the calls their turns itself.
    pacer.start_tick()
    world.tick()
    pacer.end_tick()
    assert not pacer.resting()


def test_a_stream_tells_the_step_it_last_went_out_at():
    # Steps on request end by sending the streams where they ended, unless a chunk's turn
    # just sent them there: no stamp goes out twice.
    pacer, world, wall, _ = make(0.0, step_cost=1e-5)
    assert not pacer.went_out_at('odom', 0.0)
    world.tick()
    last = world.published['odom'][-1] * TIMESTEP
    assert pacer.went_out_at('odom', last)
    assert not pacer.went_out_at('odom', last + TIMESTEP)
    assert not pacer.went_out_at('odom', last - TIMESTEP)
