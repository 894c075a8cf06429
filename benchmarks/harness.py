"""
The benchmark's ROS plumbing, shared by its sections.

A client node in this process, the package's executables run as processes, and the waits and
samples every section measures with.
"""

import contextlib
import ctypes
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time

import yaml

PACKAGE = 'service_tutorial'
PR_SET_PDEATHSIG = 1  # prctl option, from linux/prctl.h
# How soon a thread waiting for the GIL gets it where a node and its client share this process.
THREAD_SWITCH_INTERVAL = 0.0002  # s


class BenchmarkError(RuntimeError):
    """A measurement could not be taken; the message says which and why."""


def wait_until(condition, failure, *, timeout=30.0, process=None, interval=0.01):
    """Poll condition until it holds; raise BenchmarkError(failure) on a timeout."""
    deadline = time.monotonic() + timeout
    while not condition():
        if process is not None:
            process.check()
        if time.monotonic() > deadline:
            raise BenchmarkError(failure)
        time.sleep(interval)


class ExecutorThread:
    """Nodes spun by a single-threaded executor on a thread of its own."""

    def __init__(self, *nodes):
        from rclpy.executors import SingleThreadedExecutor
        self._executor = SingleThreadedExecutor()
        for node in nodes:
            self._executor.add_node(node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        from rclpy.exceptions import InvalidHandle
        while True:
            try:
                return self._executor.spin()
            except InvalidHandle:
                # A publisher or subscription destroyed by another thread while this one made
                # its wait set: the node no longer lists it, and the next wait set lacks it.
                continue

    def stop(self):
        """Shut the executor down and wait for its thread."""
        self._executor.shutdown(timeout_sec=5.0)
        self._thread.join(timeout=5.0)


class Observer:
    """A client node on an executor thread of its own: calls services, counts messages."""

    def __init__(self):
        from rclpy.node import Node
        self.node = Node('world_benchmark')
        self._executor_thread = ExecutorThread(self.node)
        self._clients = {}

    def client(self, srv_type, name):
        """Return a client of a service, made once and kept."""
        key = (srv_type, name)
        if key not in self._clients:
            self._clients[key] = self.node.create_client(srv_type, name)
        return self._clients[key]

    def wait_for_service(self, srv_type, name, *, timeout=30.0, process=None):
        """Wait until a service has a server; rclpy's own wait polls only every 0.25 s."""
        wait_until(self.client(srv_type, name).service_is_ready,
                   f'service {name} did not appear within {timeout} s', timeout=timeout,
                   process=process, interval=0.002)

    def call(self, srv_type, name, request, *, timeout=30.0):
        """Call a service and return its response, waiting on the future without polling."""
        done = threading.Event()
        future = self.client(srv_type, name).call_async(request)
        future.add_done_callback(lambda _: done.set())
        if not done.wait(timeout):
            raise BenchmarkError(f'service {name} did not answer within {timeout} s')
        return future.result()

    def call_async(self, srv_type, name, request):
        """Start a service call; return its future."""
        return self.client(srv_type, name).call_async(request)

    def timed_calls(self, srv_type, name, make_request, count, *, check=None):
        """Call a service count times; return the round-trip times in seconds."""
        samples = []
        for index in range(count):
            request = make_request(index)
            start = time.perf_counter()
            response = self.call(srv_type, name, request)
            samples.append(time.perf_counter() - start)
            if check is not None and not check(response):
                raise BenchmarkError(f'{name} failed: {response}')
        return samples

    def counter(self, msg_type, topic):
        """Count the messages arriving on a topic; return the counter and its subscription."""
        counter = [0]

        def count(_):
            counter[0] += 1
        subscription = self.node.create_subscription(msg_type, topic, count, 10)
        return counter, subscription

    def close(self):
        """Stop the executor thread and destroy the node."""
        self._executor_thread.stop()
        self.node.destroy_node()


def _die_with_parent():
    """In a child process: ask Linux for SIGTERM when the benchmark dies without stopping it."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except (OSError, AttributeError):
        pass


class NodeProcess:
    """One of the package's executables run as users run it, stopped with SIGINT."""

    def __init__(self, executable, *, node_name=None, parameters=None, ros_args=(),
                 log_dir=None):
        from ament_index_python.packages import get_package_prefix, PackageNotFoundError
        try:  # where `ros2 run` finds it, on PATH or not
            path = os.path.join(get_package_prefix(PACKAGE), 'lib', PACKAGE, executable)
        except PackageNotFoundError:
            path = None
        if path is None or not os.access(path, os.X_OK):
            raise BenchmarkError(f'executable {executable!r} of {PACKAGE} is not installed: '
                                 'run scripts/setup and source scripts/env.sh')
        self.executable = executable
        self._log_dir = log_dir or tempfile.mkdtemp(prefix='world_benchmark-')
        args = [path]
        if parameters or ros_args:
            args.append('--ros-args')
        if parameters:
            params_path = os.path.join(self._log_dir, f'{executable}.yaml')
            with open(params_path, 'w') as params_file:
                yaml.safe_dump({node_name: {'ros__parameters': parameters}}, params_file)
            args += ['--params-file', params_path]
        args += list(ros_args)
        self.log_path = os.path.join(self._log_dir, f'{executable}.log')
        self._log = open(self.log_path, 'w')
        self.process = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT,
                                        cwd=self._log_dir, preexec_fn=_die_with_parent)

    def check(self):
        """Raise BenchmarkError with the end of its log if the process has exited."""
        if self.process.poll() is not None:
            raise BenchmarkError(f'{self.executable} exited with status '
                                 f'{self.process.returncode}:\n{self.log_tail()}')

    def log_tail(self, lines=20):
        """Return the last lines the process printed."""
        self._log.flush()
        with open(self.log_path) as log_file:
            return ''.join(log_file.readlines()[-lines:])

    def cpu_time(self):
        """Return the CPU time (user and system, every thread) the process has used, in s."""
        with open(f'/proc/{self.process.pid}/stat') as stat_file:
            fields = stat_file.read().rsplit(')', 1)[1].split()
        # utime and stime are fields 14 and 15 of proc(5); fields[0] here is field 3.
        return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')

    def stop(self):
        """Stop the process with Ctrl-C, or kill it if it does not go within 10 s."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(timeout=10.0)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        self._log.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.stop()


def sim_time_sample(observer, model_name, *, timeout=30.0):
    """Return (simulation time, wall time) from one get_model_state round trip."""
    from service_tutorial.conversions import seconds_of
    from srv_interfaces.srv import GetModelState
    start = time.monotonic()
    response = observer.call(GetModelState, '/mujoco/get_model_state',
                             GetModelState.Request(model_name=model_name), timeout=timeout)
    end = time.monotonic()
    if not response.success:
        raise BenchmarkError(f'get_model_state {model_name}: {response.status_message}')
    return seconds_of(response.header.stamp), 0.5 * (start + end), response


def wait_for_world(observer, process, model_name, *, tries=6):
    """
    Wait until the world process answers get_model_state for model_name.

    A service can be ready before its server has matched the client's response reader; a
    response sent in that gap is lost (a known DDS race), so a first call that gets no answer
    within 5 s is made again.
    """
    from srv_interfaces.srv import GetModelState
    observer.wait_for_service(GetModelState, '/mujoco/get_model_state', process=process)
    for attempt in range(tries):
        try:
            return sim_time_sample(observer, model_name, timeout=5.0)
        except BenchmarkError:
            process.check()
            if attempt == tries - 1:
                raise


def wait_until_gone(observer, srv_type, name, *, timeout=10.0):
    """Wait until no server offers a service any more (a stopped world left the graph)."""
    client = observer.client(srv_type, name)
    deadline = time.monotonic() + timeout
    while client.service_is_ready() and time.monotonic() < deadline:
        time.sleep(0.01)


def wait_until_world_gone(observer):
    """Wait until a stopped world's services have left the graph."""
    from srv_interfaces.srv import GetModelState
    wait_until_gone(observer, GetModelState, '/mujoco/get_model_state')


class ClosedOnExit:
    """A with-statement's resource whose close() runs when the block ends, however it ends."""

    def __enter__(self):
        return self

    def __exit__(self, *exc_info):
        self.close()


def wait_for_count(counter, process, what, *, timeout=30.0):
    """Wait until a message counter has counted one; fail early if the process exits."""
    wait_until(lambda: counter[0] != 0, f'no {what} within {timeout} s', timeout=timeout,
               process=process)


@contextlib.contextmanager
def prompt_thread_switches(seconds=THREAD_SWITCH_INTERVAL):
    """
    Let a thread waiting for the GIL in after seconds rather than Python's 5 ms, for a while.

    A node run in this process on an executor thread shares the interpreter with its client: a
    client whose answer came while the node goes on working (making the topics of robots just
    spawned, building its next wait set) waits for the GIL, up to 5 ms each time it needs it,
    which a client in a process of its own never does.
    """
    saved = sys.getswitchinterval()
    sys.setswitchinterval(seconds)
    try:
        yield
    finally:
        sys.setswitchinterval(saved)


@contextlib.contextmanager
def quiet_console(path):
    """Send this process's stderr (where in-process nodes log) to a file for a while."""
    sys.stderr.flush()
    saved = os.dup(2)
    with open(path, 'a') as log_file:
        os.dup2(log_file.fileno(), 2)
    try:
        yield
    finally:
        sys.stderr.flush()
        os.dup2(saved, 2)
        os.close(saved)
