"""
The main() of every executable here: rclpy up, one node, its work, and a clean shutdown.

rclpy.init() comes first, then the node is made and does its work; Ctrl-C (KeyboardInterrupt,
or for a server spinning, a flag it looks at) and a shutdown from outside
(ExternalShutdownException) end it quietly, and in every case the node is destroyed and rclpy
shut down. Errors a program expects are printed as
'<program>: <error>' on stderr and give exit status 1.
"""

import contextlib
import faulthandler
import os
import signal
import sys
import threading

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.utilities import remove_ros_args

# Wall time the middleware has to let a stopping program's node go, in s. Fast DDS 2.14 can spin
# for ever in the participant's destruction (DomainParticipant::set_listener, seen once in about
# ten stops of a parameter_bridge here); the program then ends anyway, with its own status.
LEAVING_TIME = 10.0
# A hang that holds the GIL stops that timer too; faulthandler's watchdog, a thread that needs
# no GIL, then prints where each thread is and ends the program (status 1) this much later, in s.
WATCHDOG_GRACE = 5.0
# Wall time a spinning server waits for work before it looks again whether to stop, in s: a
# Ctrl-C that lands while the executor is being made wakes nothing.
SIGNAL_LOOK_PERIOD = 0.25


def program_arguments(args=None):
    """Return the program's own arguments: args or sys.argv without its name and ROS part."""
    return remove_ros_args(sys.argv if args is None else args)[1:]


def run_node(make_node, work, *, args=None, program='', errors=(), interrupted_status=1):
    """
    Make a node, return work(node) as the exit status; stop cleanly whatever happens.

    errors: exception classes that are reported on stderr (status 1) rather than raised.
    interrupted_status: the status after Ctrl-C or an external shutdown.
    """
    rclpy.init(args=args)
    node = None
    status = 1  # an unexpected error's, raised
    try:
        node = make_node()
        status = work(node)
    except errors as error:
        print(f'{program}: {error}', file=sys.stderr)
        status = 1
    except (KeyboardInterrupt, ExternalShutdownException):
        status = interrupted_status
    except Exception:
        # Ctrl-C shuts the context down under a running callback, which then fails: that is
        # the program stopping, not an error of its own.
        if rclpy.ok():
            raise
        status = interrupted_status
    finally:
        leave_anyway = threading.Timer(LEAVING_TIME, _leave, (status,))
        leave_anyway.daemon = True
        leave_anyway.start()
        faulthandler.dump_traceback_later(LEAVING_TIME + WATCHDOG_GRACE, exit=True)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        faulthandler.cancel_dump_traceback_later()
        leave_anyway.cancel()
    return status


def _leave(status):
    """End the process with status now, as main() would have, while rclpy hangs in shutdown."""
    print(f'{os.path.basename(sys.argv[0])}: the middleware did not let the node go within '
          f'{LEAVING_TIME:g} s; ending anyway', file=sys.stderr)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status or 0)


def spin_node(make_node, *, args=None, done=None):
    """
    Make a node and spin it until Ctrl-C or shutdown; the main() of a server.

    done: a function of the node that returns a Future; the server also ends when it is done.
    """
    interrupted = threading.Event()
    with _interrupt_sets(interrupted):
        return run_node(make_node, lambda node: _spin(node, interrupted, done), args=args,
                        interrupted_status=None)


@contextlib.contextmanager
def _interrupt_sets(event):
    """
    Let Ctrl-C set event, rather than raise KeyboardInterrupt, within the block.

    rclpy's SIGINT handler wakes the executors, shuts the contexts down and passes the signal on
    to Python's, which raises KeyboardInterrupt at whatever the main thread runs next: once the
    spinning had ended, in the teardown, which it escaped (exit status 1). Set before
    rclpy.init, which keeps the handler it finds to pass signals on to. Only the main thread
    may set a handler: elsewhere (a test that runs main()) nothing changes.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, lambda signum, frame: event.set())
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _spin(node, interrupted, done):
    """
    Spin node on a thread of its own until Ctrl-C, shutdown or done; raise what a callback raised.

    The main thread only waits, so that it sees Ctrl-C whatever holds the spinning up: a
    callback that blocks, or the middleware's wait, seen hung far past its timeout under load.
    The spinning normally ends within a turn; held up longer than LEAVING_TIME, it is left
    behind (a daemon thread) and the program goes on to let its node go.
    """
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    finished = None if done is None else done(node)
    if finished is not None:
        finished.add_done_callback(lambda _: executor.wake())
    ended = threading.Event()
    failures = []

    def spin():
        try:
            while rclpy.ok() and not interrupted.is_set() and not (finished and finished.done()):
                executor.spin_once(timeout_sec=SIGNAL_LOOK_PERIOD)
        except BaseException as error:
            failures.append(error)
        finally:
            ended.set()

    spinner = threading.Thread(target=spin, name=f'spin {node.get_name()}', daemon=True)
    spinner.start()
    try:
        while not ended.wait(SIGNAL_LOOK_PERIOD) and not interrupted.is_set():
            pass
        executor.wake()
        if ended.wait(LEAVING_TIME) and failures:
            raise failures[0]
    finally:
        executor.shutdown(timeout_sec=0)
