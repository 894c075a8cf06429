"""
An executor that can tell when its nodes have handled everything that came to them.

A test steps the world, and then the test's own nodes react: to odometry, to /clock, to their
timers. SettlingExecutor.settle() returns once the executor has run every callback that was
ready when it was asked, and those that became ready on the way, and found nothing more to do.
Within a process, DDS hands a message to the readers of the same Context as it is published:
what the world published before it answered is there for the nodes, and what they publish in
reaction is there for the world when settle() returns. So the next steps start with it, and a
test steps in lockstep with its nodes, the same way every time.
"""

import threading

from rclpy.executors import ConditionReachedException, ShutdownException
from rclpy.executors import SingleThreadedExecutor, TimeoutException


class SettlingExecutor(SingleThreadedExecutor):
    """A single-threaded executor whose settle() waits until nothing is left to run."""

    def __init__(self, *, context):
        super().__init__(context=context)
        self._settled = threading.Event()
        self._stopping = False
        self.failure = None  # what a callback raised: it ended the spinning
        # Ends a wait for work: a test asked whether the nodes settled (one function, kept, so
        # that the executor's generator of ready callbacks is not made anew on every call).
        self._asked = lambda: not self._settled.is_set()

    def spin(self):
        """Run callbacks until shutdown or one raises, settling whenever nothing is left."""
        try:
            while self.context.ok() and not self._stopping:
                if self._run_ready() == 0:
                    self._settled.set()
                    self._run_one(timeout_sec=None, until=self._asked)
        except Exception as error:  # kept for the test's thread, which raises it
            self.failure = error
            self._settled.set()

    def _run_ready(self):
        """Run every callback ready now, from a fresh look at the wait set; return how many."""
        ran = 0
        while self._run_one(timeout_sec=0.0):
            ran += 1
        return ran

    def _run_one(self, *, timeout_sec, until=None):
        """Run a ready callback, waiting up to timeout_sec or until until(); tell if one ran."""
        try:
            handler, _, _ = self.wait_for_ready_callbacks(
                timeout_sec=timeout_sec, condition=until or (lambda: False))
        except (ConditionReachedException, ShutdownException, TimeoutException):
            return False
        handler()
        if handler.exception() is not None:
            raise handler.exception()
        return True

    def settle(self, timeout):
        """
        Wait until every callback ready now, and any that follows, has run; tell if in time.

        Raises what a callback raised, if one did: the node stopped there.
        """
        if self.failure is None:
            self._settled.clear()
            self.wake()  # a look at what is ready, even if the executor was waiting
            settled = self._settled.wait(timeout)
        if self.failure is not None:
            raise self.failure
        return settled

    def shutdown(self, timeout_sec=None):
        """Stop spinning (the spin thread ends) and let the nodes go."""
        self._stopping = True
        return super().shutdown(timeout_sec)
