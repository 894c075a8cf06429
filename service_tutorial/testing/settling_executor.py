"""
An executor that can tell when its nodes have handled everything that came to them.

A test steps the world, and then the test's own nodes react: to odometry, to /clock, to their
timers. SettlingExecutor.settle() returns once the executor has run every callback that was
ready when it was asked, and those that became ready on the way, and found nothing more to do.
Within a process, DDS hands a message to the readers of the same Context as it is published:
what the world published before it answered is there for the nodes, and what they publish in
reaction is there for the world when settle() returns. So the next steps start with it, and a
test steps in lockstep with its nodes, the same way every time.

Both executors here stop spinning on request (stop()), so that a test's thread ends before its
executor is shut down.
"""

import threading

from rclpy.executors import ConditionReachedException, ShutdownException
from rclpy.executors import SingleThreadedExecutor, TimeoutException


class StoppableExecutor(SingleThreadedExecutor):
    """
    A single-threaded executor whose spinning stop() ends before the executor is shut down.

    rclpy's Executor.shutdown() destroys the executor's guard condition without waiting for a
    spin on another thread to leave its wait set, which then fails on the destroyed guard
    (AttributeError: 'NoneType' object has no attribute 'handle'). So a thread that spins an
    executor is stopped and joined first, and the executor shut down after.
    """

    def __init__(self, *, context):
        super().__init__(context=context)
        self._stopping = False
        self._stop_asked = lambda: self._stopping  # one function, kept (see _run_one)
        self._awaiting = set()  # tasks of coroutine callbacks that await something

    def spin(self):
        """Run callbacks until stop(), the Context's shutdown or a callback raises."""
        while self.context.ok() and not self._stopping:
            self._run_one(timeout_sec=None, until=self._stop_asked)

    def stop(self):
        """End spin() on its thread: it returns once the callback it runs, if any, has run."""
        self._stopping = True
        self.wake()

    def _run_one(self, *, timeout_sec, until):
        """
        Run a ready callback, waiting up to timeout_sec or until until(); tell if one ran.

        A coroutine callback that awaits something (an action's execute callback awaiting the
        end of its goal) is handed out by rclpy first on every turn, before it waits for work,
        and resumed to see whether it can go on: resuming it counts as a callback run only if
        it ended, and the turn goes on to what else is ready; once the same one comes again, a
        whole turn found nothing else. until is a function kept from call to call: rclpy makes
        its generator of ready callbacks anew whenever the arguments change.
        """
        resumed = set()
        while True:
            try:
                handler, _, _ = self.wait_for_ready_callbacks(timeout_sec=timeout_sec,
                                                              condition=until)
            except (ConditionReachedException, ShutdownException, TimeoutException):
                return False
            if handler in resumed:
                return False
            was_awaiting = handler in self._awaiting
            handler()
            if handler.exception() is not None:
                raise handler.exception()
            if handler.done() or handler.cancelled():
                self._awaiting.discard(handler)
                return True
            self._awaiting.add(handler)
            if not was_awaiting:
                return True
            resumed.add(handler)


class SettlingExecutor(StoppableExecutor):
    """A single-threaded executor whose settle() waits until nothing is left to run."""

    def __init__(self, *, context):
        super().__init__(context=context)
        self._settled = threading.Event()
        self.failure = None  # what a callback raised: it ended the spinning
        # Ends a wait for work: a test asked whether the nodes settled, or the spinning is to
        # stop (one function, kept).
        self._asked = lambda: self._stopping or not self._settled.is_set()
        self._ready_now = lambda: self._stopping

    def spin(self):
        """Run callbacks until stop() or shutdown or one raises, settling whenever none is left."""
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
        while self._run_one(timeout_sec=0.0, until=self._ready_now):
            ran += 1
        return ran

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
