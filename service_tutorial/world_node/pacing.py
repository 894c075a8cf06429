"""
When the world node steps the physics and publishes its streams: the pacing scheduler.

No ROS and no world here: the node hands in simulation time, and the wall and CPU clocks are
parameters, so the tests drive a Pacer with fake clocks.

Streams (/clock, odometry, joint states) fall due at their rates in simulation time, with half
a step of slack, since simulation time is a sum of steps and carries rounding errors. In real
time (real_time_factor above 0) a tick steps as far as the wall clock says, in chunks that end
where a stream that carries the world's state (odometry, joint states) falls due. /clock only
tells the time, so it does not end chunks (TIME_ONLY_STREAMS): each of its turns that a chunk
stepped past goes out after the chunk, stamped with the step at its turn. A chunk of 2 steps
per /clock message cost more than the steps. A real-time tick as long as a stream's period
ends at the last turn of a stream of state (_to_last_turn): the world lags the wall clock by up
to MAX_TICK_SIMULATED more, and its ticks end at the same steps however early or late the wall
clock's ticks come. Free-running (real_time_factor 0) a tick steps for
a budget of wall time, and each stream is also held to its rate in wall time: far faster than
real time, the simulated rates would cost more than the physics. The streams of state end
chunks at their turns in wall time, /clock goes out after the first chunk past its turn. What a
step costs is learnt as the world steps (_learn_step_cost), and chunks end within WALL_SLACK of
a turn or a tick's deadline: 10,000 steps of ten robots on request took about 100 chunks, where
chunks that each ended at /clock's turn, just short of it, took 1,100 (a tenth of the time
went to the chunks and not to the physics).

The executor's turn between two ticks costs CPU time that grows with the node's topics (about
0.4 ms with 50 robots in real time), so ticks are spaced to keep it a small share of the time.
Free-running, a tick steps EXECUTOR_SHARE times as long as a turn (STEP_BUDGET to
MAX_STEP_BUDGET); in real time, ticks come every REAL_TIME_SHARE turns (REAL_TIME_PERIOD to
MAX_REAL_TIME_PERIOD, and no more than MAX_TICK_SIMULATED of simulated time apart); paused,
there is nothing to step and ticks come every PAUSED_TICK_PERIOD, and /clock is said again
every PAUSED_CLOCK_PERIOD of wall time (repeat_due), so that a late joiner learns the time.

A paused world steps only on request (StepSimulation): a tick then steps as free-running does,
up to the count asked for (step_on_request, requested_chunks).

A tick that ran past twice MAX_STEP_BUDGET (steps that each take long: sensors that cast or
publish a lot at every step, frames of a large camera handed on) is followed by a rest as long as
the tick (MAX_REST at most): the node does not step until it ends (resting), so the executor
answers every call waiting, one after the other, before the next tick; otherwise it answers one
call of each service between two ticks. Such a world gives its services about half of its
thread's time. A tick a little past its budget (a chunk of steps that took longer than its
estimate) rests only as long as it ran over: resting as long as the tick made StepSimulation's
10,000 steps a quarter slower. Free-running ticks back to back leave the executor's turn after
each tick to the calls that came during it: the executor would otherwise run the next tick
first, and every call, get_model_list too, waited one and a half ticks (85 ms at the 50 ms
budget). A call answered then puts the next tick off by FOLLOW_UP (answered), for the caller's
next call. Steps on request keep every turn (the node says which ticks are back to back).

While a spawn or a delete keeps the world busy, simulation time stands still (hold), as in
Gazebo; the world does not run fast afterwards to make up for it.

The real-time factor and the streams' periods may change at run time (set_real_time_factor,
set_period): the pace changes from the current simulation time on, and a stream's next turn
moves by the change of its period.
"""

import inspect
import math
import time

# The world node's publication streams: /clock, and its models' odometry and joint states.
CLOCK_STREAM = 'clock'
ODOMETRY_STREAM = 'odom'
JOINT_STATES_STREAM = 'joint_states'
TIME_ONLY_STREAMS = (CLOCK_STREAM,)
STEP_BUDGET = 0.005
EXECUTOR_SHARE = 40.0
MAX_STEP_BUDGET = 0.05
REAL_TIME_SHARE = 60.0
REAL_TIME_PERIOD = 0.002
MAX_REAL_TIME_PERIOD = 0.02
# At most this much simulated time per tick: a command waits for the next tick, so a tick of
# more would delay stop commands by more than this of simulated time at high factors.
MAX_TICK_SIMULATED = 0.02
PAUSED_TICK_PERIOD = 0.02
PAUSED_CLOCK_PERIOD = 0.1
# Free-running, a stream is due this share of its period before its turn in wall time, and a
# tick ends this share of its budget before its deadline: a chunk's steps are estimated, and
# a chunk of the few steps left before a turn costs more than the steps.
WALL_SLACK = 0.1
# What a step costs is learnt from the chunks of steps: each sum keeps this much of the last.
COST_MEMORY = 0.8
# Further behind real time than this (s), the machine cannot keep up: do not try to catch up.
# A longer stall loses simulated time: the commands of nodes on simulation time would
# otherwise come late by as much as the world raced to make it up.
MAX_LAG = 0.1
# The longest rest after a tick that ran past its budget, in s of wall time.
MAX_REST = 0.2
# Spawns and deletes may put the next tick off (see hold), but not for longer than this (s).
MAX_DEFERRAL = 0.1
# Ticks back to back, the next tick waits this long after a call is answered (s), for the
# caller's next call: a local client sends it about 1 ms after the answer.
FOLLOW_UP = 0.01
NANOSECONDS = 1_000_000_000


def heard_by_pacer(pacer, callback):
    """Return a service callback that tells pacer (Pacer.answered) each time it has answered."""
    def answer(request, response):
        try:
            return callback(request, response)
        finally:
            pacer.answered()

    async def answer_when_done(request, response):  # a callback that waits (stepping)
        try:
            return await callback(request, response)
        finally:
            pacer.answered()
    return answer_when_done if inspect.iscoroutinefunction(callback) else answer


class Pacer:
    """Decides how far each tick steps, how often ticks come, and which streams are due."""

    def __init__(self, *, timestep, real_time_factor, periods, wall_clock=time.monotonic,
                 cpu_clock=time.thread_time):
        """Pace a world of this timestep; periods maps each stream's name to its period (s)."""
        self.timestep = timestep
        self.real_time_factor = max(0.0, real_time_factor)
        self._on_request = False
        self._periods = dict(periods)
        self._state_streams = [name for name in self._periods if name not in TIME_ONLY_STREAMS]
        self._next_sim = dict.fromkeys(self._periods, 0.0)
        self._next_wall = dict.fromkeys(self._periods, 0.0)
        self._published_at = dict.fromkeys(self._periods)  # simulation time, or None
        self._wall_clock = wall_clock
        self._cpu_clock = cpu_clock
        self.step_wall_time = 1e-5  # running estimate of one physics step, in wall seconds
        self._cost_steps = self._cost_seconds = 0.0  # its sums (_learn_step_cost)
        self.executor_turn = 0.0  # running estimate of the CPU time between two ticks
        self._tick_end_cpu = None
        self._tick_started = 0.0  # wall time
        self._rest_until = 0.0  # wall time
        self._turn_owed = False  # the executor's next turn goes to the calls waiting
        self._back_to_back = False  # the last tick was followed at once by the next
        self._tick_ended = 0.0  # wall time
        # Simulation time is tied to the wall clock at the first tick in real time, not when
        # the world is made: the time it takes the node to start spinning is not made up.
        self._wall_anchor = None
        self._sim_anchor = 0.0
        self._next_repeat = 0.0

    # --- ticks --------------------------------------------------------------------------------

    @property
    def free_running(self):
        """Tell whether the world steps as fast as it can: factor 0, or steps on request."""
        return self.real_time_factor == 0.0 or self._on_request

    def step_on_request(self, on):
        """
        Pace a paused world's steps on request as free-running (on), or end that.

        Whatever the real-time factor, steps on request go as fast as the machine can, and so
        every stream is held to its rate in wall time too, as free-running.
        """
        self._on_request = on
        if not on:  # wall-time turns only hold streams back while free-running
            self._next_wall = dict.fromkeys(self._periods, 0.0)

    @property
    def first_tick_period(self):
        """Return the step timer's period to start with, in s (0: every executor turn)."""
        return 0.0 if self.free_running else REAL_TIME_PERIOD

    def anchor(self, sim_time):
        """Tie simulation time to the wall clock from now on (start, pause, reset)."""
        self._wall_anchor = self._wall_clock()
        self._sim_anchor = sim_time

    def hold(self, busy_since):
        """
        Let simulation time stand still while the world was busy (a spawn, a delete) until now.

        busy_since is a time of the wall clock. As in Gazebo, the world does not race to make
        up the time afterwards: the steps that were due before are still taken, the time the
        world was busy is not. Return whether the next tick may come a whole period from now,
        so that a client's next call finds the executor free: calls back to back put stepping
        off by MAX_DEFERRAL at most.
        """
        if self._wall_anchor is not None:
            self._wall_anchor += max(0.0, self._wall_clock() - busy_since)
        return busy_since - self._tick_started < MAX_DEFERRAL

    def set_real_time_factor(self, real_time_factor, sim_time):
        """Run at another pace (0: free-running) from simulation time sim_time on."""
        self.real_time_factor = max(0.0, real_time_factor)
        # Wall-time turns only hold streams back while free-running.
        self._next_wall = dict.fromkeys(self._periods, 0.0)
        self.anchor(sim_time)

    def repeat_due(self):
        """Tell whether a paused world should say its time again (every PAUSED_CLOCK_PERIOD)."""
        wall = self._wall_clock()
        if wall < self._next_repeat:
            return False
        self._next_repeat = wall + PAUSED_CLOCK_PERIOD
        return True

    def start_tick(self):
        """Note when a tick starts, and the CPU time the executor spent since the last one."""
        self._tick_started = self._wall_clock()
        now = self._cpu_clock()
        if self._tick_end_cpu is not None:
            # Follows the cheapest recent turns: a slow service call is not overhead.
            self.executor_turn = max(0.0, min(now - self._tick_end_cpu,
                                              1.05 * self.executor_turn + 1e-6))

    def end_tick(self, *, back_to_back=False):
        """
        Note when a tick ended, in CPU time, and rest after a tick that ran past its budget.

        back_to_back: the next tick would come on the very next executor turn (a timer of
        period 0). That turn is then given to the calls that came during this tick (resting),
        or else the executor would run the next tick before them and a call would wait for
        up to two ticks.
        """
        self._tick_end_cpu = self._cpu_clock()
        wall = self._wall_clock()
        took = wall - self._tick_started
        if took > 2.0 * MAX_STEP_BUDGET:  # steps that each take long: half the time to calls
            rest = min(took, MAX_REST)
        else:  # a chunk of steps that took a little longer than its estimate
            rest = max(0.0, took - MAX_STEP_BUDGET)
        self._rest_until = wall + rest
        self._turn_owed = self._back_to_back = back_to_back
        self._tick_ended = wall

    def answered(self):
        """
        Note a call answered: ticks back to back, the next waits FOLLOW_UP for the next call.

        Without it, a client calling again at once always found a tick begun and waited for a
        whole tick. Calls that keep coming put the next tick off by MAX_DEFERRAL at most.
        """
        if self._back_to_back:
            wall = self._wall_clock()
            self._rest_until = max(self._rest_until, min(wall + FOLLOW_UP,
                                                         self._tick_ended + MAX_DEFERRAL))

    def resting(self):
        """Tell whether the next tick must wait: for a rest (end_tick), or for one turn."""
        if self._wall_clock() < self._rest_until:
            return True
        owed, self._turn_owed = self._turn_owed, False
        return owed

    def tick_period_ns(self, paused):
        """Return the step timer's period for the current state, in whole milliseconds."""
        if paused:
            return round(PAUSED_TICK_PERIOD * NANOSECONDS)
        if self.free_running:
            return 0
        longest = min(MAX_REAL_TIME_PERIOD, MAX_TICK_SIMULATED / self.real_time_factor)
        # Never below REAL_TIME_PERIOD: far faster than real time, a period of 0 would spin.
        period = max(REAL_TIME_PERIOD, min(longest, REAL_TIME_SHARE * self.executor_turn))
        return round(period * 1e3) * 1_000_000

    def chunks(self, sim_time, other_due=lambda: math.inf):
        """
        Yield the step counts of one tick; the caller steps and publishes after each.

        sim_time() gives the world's time now; other_due() the simulation time at which
        something else (the camera) wants the stepping to stop, or infinity.
        """
        if self.free_running:
            yield from self._free_running_chunks(sim_time, other_due)
        else:
            yield from self._real_time_chunks(sim_time, other_due)

    def _real_time_chunks(self, sim_time, other_due):
        if self._wall_anchor is None:
            self.anchor(sim_time())
        wall = self._wall_clock()
        target = self._sim_anchor + (wall - self._wall_anchor) * self.real_time_factor
        behind = int((target - sim_time()) / self.timestep)
        if behind > MAX_LAG / self.timestep:
            behind = int(MAX_LAG / self.timestep)
            # Go on from where this tick ends, as if the wall clock had waited for it.
            self.anchor(sim_time() + behind * self.timestep)
        behind = self._to_last_turn(sim_time(), behind)
        # However far behind, a tick steps for MAX_STEP_BUDGET of wall time at most, so that
        # calls are answered between two ticks even when steps are slow (lasers cast at every
        # step): the world then runs slower than real time, as it does when it cannot keep up.
        deadline = wall + MAX_STEP_BUDGET
        while behind > 0:
            start = self._wall_clock()
            if start >= deadline:
                return
            steps = self.steps_to_next_due(sim_time(), other_due(), limit=behind)
            steps = max(1, min(steps, int((deadline - start)
                                          / max(self.step_wall_time, 1e-7))))
            yield steps
            behind -= steps
            self._learn_step_cost(steps, self._wall_clock() - start)

    def _to_last_turn(self, now, steps):
        """
        Return the steps of a real-time tick of steps: to the last turn of a stream of state.

        A tick about as long as a stream's period or longer ends where one of the streams of
        state falls due, the rest waiting for the next tick if it is MAX_TICK_SIMULATED at
        most; a tick that would end a step short of a turn takes that step too. Ticks then
        take one chunk each, not a chunk to the turn and one past it, and end at the same
        steps whether the wall clock ticks a little early or late: a command taken at a tick
        takes effect as long after the /clock message it was sent on, whichever tick it is.
        """
        last = None
        for name in self._state_streams:
            # A stream due now goes out after the first step (a chunk takes one at least).
            turn = max(self._next_sim[name], now + self.timestep)
            period = self._periods[name]
            if (steps + 1) * self.timestep < period - 0.5 * self.timestep:
                continue  # a short tick: it steps as far as the wall clock went
            within = math.floor(((now + (steps + 0.5) * self.timestep) - turn) / period)
            if within < 0:  # no turn within: step to the first if it is one step past
                within = 0 if turn <= now + (steps + 1.5) * self.timestep else None
            if within is not None:
                turn_steps = round((turn + within * period - now) / self.timestep)
                last = turn_steps if last is None else max(last, turn_steps)
        if last is None or (steps - last) * self.timestep > MAX_TICK_SIMULATED + 1e-9:
            return steps
        return last

    def requested_chunks(self, count, sim_time, other_due=lambda: math.inf):
        """
        Yield the step counts of one tick of a paused world's steps on request (step_on_request).

        As free-running: a tick takes count steps at most, and for no longer than its budget of
        wall time, so that services are answered in between.
        """
        yield from self._free_running_chunks(sim_time, other_due, count)

    def _free_running_chunks(self, sim_time, other_due, limit=math.inf):
        budget = min(MAX_STEP_BUDGET, max(STEP_BUDGET, EXECUTOR_SHARE * self.executor_turn))
        deadline = self._wall_clock() + budget
        while limit > 0:
            start = self._wall_clock()
            # A chunk of the last few steps would cost more than the steps: the next tick
            # comes at once anyway (free-running, ticks are back to back).
            if start >= deadline - WALL_SLACK * budget:
                return
            steps = min(limit, self.free_running_chunk(sim_time(), start, deadline, other_due()))
            limit -= steps
            yield steps
            self._learn_step_cost(steps, self._wall_clock() - start)

    def _learn_step_cost(self, steps, seconds):
        """
        Follow what a step costs from a chunk of steps that took seconds of wall time.

        A ratio of sums over the last chunks: what a chunk costs besides its steps (publishing,
        Python) weighs as little as it does in the stepping. An average of each chunk's seconds
        per step took a chunk of one step, which costs about two, as the rule, and chunks shrank
        before each stream's turn in wall time: four or five of them per turn instead of one.
        """
        self._cost_steps = COST_MEMORY * self._cost_steps + steps
        self._cost_seconds = COST_MEMORY * self._cost_seconds + seconds
        self.step_wall_time = self._cost_seconds / self._cost_steps

    def steps_to_next_due(self, now, other_due=math.inf, *, limit):
        """Return the steps until a stream of state (or other_due) falls due, 1 to limit."""
        due = min([self._next_sim[name] for name in self._state_streams] + [other_due])
        # Half a step of slack, as in take_due().
        steps = (due - now) / self.timestep - 0.5
        if steps >= limit:  # also when nothing is due at all
            return limit
        return max(1, math.ceil(steps))

    def free_running_chunk(self, now, wall, deadline, other_due=math.inf):
        """Return the steps until a stream falls due (simulation and wall time) or deadline."""
        per_step = max(self.step_wall_time, 1e-7)
        steps = (deadline - wall) / per_step
        for name in self._state_streams:
            steps = min(steps, max((self._next_sim[name] - now) / self.timestep,
                                   (self._next_wall[name] - wall) / per_step))
        steps = min(steps, (other_due - now) / self.timestep)
        return max(1, math.ceil(steps - 0.5))

    # --- streams ------------------------------------------------------------------------------

    def take_due(self, now):
        """
        Return (stream, stamp) for each turn due by simulation time now, in order of stamps.

        A stream that carries state is stamped now. In real time, a time-only stream (/clock)
        gives each turn the last chunk stepped past, stamped with the step at its turn, one
        per step at most, and keeps to its period on average; the stream is then scheduled
        for its next turn.
        """
        # Half a step of slack: simulation time is a sum of steps and carries rounding errors.
        soon = now + 0.5 * self.timestep
        wall = self._wall_clock()
        due = []
        for name in self._periods:
            turn = self._next_sim[name]
            if soon < turn or wall < self._next_wall[name] - WALL_SLACK * self._periods[name]:
                continue
            if name in TIME_ONLY_STREAMS and not self.free_running and now - turn < MAX_LAG:
                period = self._periods[name]
                while turn <= soon:
                    # A turn's step: the one that ended within half a step of it.
                    stamp = now - self.timestep * math.floor((now - turn) / self.timestep + 0.5)
                    due.append((name, stamp))
                    turn = max(turn + period, stamp + self.timestep)
                self._next_sim[name] = turn
            else:
                due.append((name, now))
                self.published(name, now)
        return sorted(due, key=lambda item: item[1])  # stable: streams keep their order

    def published(self, name, now):
        """Schedule a stream's next turn after it was published at simulation time now."""
        period = self._periods[name]
        self._next_sim[name] = now + period
        self._published_at[name] = now
        if self.free_running:
            # Within the slack before its turn, a stream goes out early, and its next turn is
            # a whole period after this one: on average, it keeps to its rate.
            self._next_wall[name] = max(self._next_wall[name] + period,
                                        self._wall_clock() + (1.0 - WALL_SLACK) * period)
        else:
            self._next_wall[name] = 0.0

    def went_out_at(self, name, now):
        """Tell whether a stream was last published at simulation time now (published())."""
        last = self._published_at[name]
        return last is not None and abs(last - now) < 0.5 * self.timestep

    def set_period(self, name, period):
        """Give a stream another period (s); its next turn moves by the difference."""
        change = period - self._periods[name]
        self._periods[name] = period
        self._next_sim[name] += change
        if self._next_wall[name]:
            self._next_wall[name] += change

    def restart(self, now, names):
        """Make streams due at once, at simulation time now (after a reset)."""
        for name in names:
            self._next_sim[name] = now
            self._next_wall[name] = 0.0
