"""
Stepping a paused world on request: exactly N steps, taken by the step timer tick by tick.

A request (StepSimulation, the SimulateSteps action) gets a budget of wall time per tick of the
node's step timer (Pacer.requested_chunks), so the world's other services are answered between
two ticks however many steps were asked for; what falls due on the way (/clock, odometry, joint
states, sensors) is published as when free-running (held to its rate in wall time too), and
the time, odometry and joint states where the steps end. One request runs at a time. Its future
completes with None once every step is taken, or with a sentence that says why it ended early
and after how many steps. The world stays paused throughout.
"""

import time

from rclpy.task import Future
from service_tutorial.world_node.pacing import CLOCK_STREAM, JOINT_STATES_STREAM
from service_tutorial.world_node.pacing import ODOMETRY_STREAM

# Wall time between two progress reports of a request, in s: 10 Hz, and one at the end.
PROGRESS_PERIOD = 0.1
# The streams that carry the models' state: published where a request's steps end.
STATE_STREAMS = (ODOMETRY_STREAM, JOINT_STATES_STREAM)


class StepRequest:
    """A client's N steps: how many are taken, and a future that completes when they end."""

    def __init__(self, count, *, progress=None, cancelled=None):
        """progress(taken, remaining) hears how far it got; cancelled() may ask it to stop."""
        self.count = count
        self.taken = 0
        self.future = Future()
        self._progress = progress
        self._cancelled = cancelled
        self._next_progress = time.monotonic() + PROGRESS_PERIOD

    @property
    def remaining(self):
        """Return the steps still to take."""
        return self.count - self.taken

    def cancelled(self):
        """Tell whether the client asked for the stepping to stop."""
        return self._cancelled is not None and self._cancelled()

    def report_progress(self, *, final=False):
        """Tell the client how far the steps got: every PROGRESS_PERIOD, and at the end."""
        wall = time.monotonic()
        if self._progress is not None and (final or wall >= self._next_progress):
            self._next_progress = wall + PROGRESS_PERIOD
            self._progress(self.taken, self.remaining)

    def end(self, why=None):
        """Complete the future: None when every step was taken, else why it ended early."""
        self.report_progress(final=True)
        self.future.set_result(why)


class RequestedSteps:
    """The world node's stepping on request: one request at a time, a share of every tick."""

    def __init__(self, node):
        """Step the world of node (a MujocoWorld) with its pacer, publishing what falls due."""
        self.node = node
        self.current = None

    @property
    def busy(self):
        """Tell whether a request is being stepped."""
        return self.current is not None

    def start(self, count, **options):
        """Begin count steps (options: StepRequest's); return the request, or None if busy."""
        if self.current is not None:
            return None
        self.current = StepRequest(count, **options)
        # Free-running until the request ends: a stream's turn in wall time outlasts a tick.
        self.node.pacer.step_on_request(True)
        # Ticks come on every executor turn while steps are due (see MujocoWorld.step_callback).
        self.node.step_timer.timer_period_ns = 0
        self.node.step_timer.reset()
        return self.current

    def tick(self):
        """Take the current request's steps for one tick's budget, publishing what falls due."""
        request, node = self.current, self.node
        if request.cancelled():
            self.stop('cancelled')
            return
        world, pacer = node.world, node.pacer
        for steps in pacer.requested_chunks(request.remaining, lambda: world.time,
                                            lambda: node.camera_stream.next_due):
            world.step(steps, even_if_paused=True)
            request.taken += steps
            node.publish_due()
        if request.remaining > 0:
            request.report_progress()
            return
        pacer.step_on_request(False)
        # Where the steps ended, whatever the streams' rates: the time, odometry, joint states,
        # each unless the last chunk's turn already sent it there (no stamp goes out twice).
        now = world.time
        if not pacer.went_out_at(CLOCK_STREAM, now):
            node.publish_clock()
        pacer.restart(now, [name for name in STATE_STREAMS if not pacer.went_out_at(name, now)])
        node.publish_due()
        self.current = None
        request.end()

    def stop(self, reason):
        """End the request in progress early, saying why (a sentence's start: 'cancelled')."""
        request, self.current = self.current, None
        self.node.pacer.step_on_request(False)
        if request is not None:
            request.end(f'{reason} after {request.taken} of {request.count} steps')
