"""
Shared pytest harness: an isolated ROS graph, nodes on real executors, the world node, programs.

Every test session claims a ROS_DOMAIN_ID that no other run on this machine holds and keeps
discovery on localhost, so parallel runs never see each other's nodes. rclpy is initialised
once per session, only when a test asks for it; the core tests never touch ROS.
"""

import os
import subprocess
import threading
import time

import pytest
from service_tutorial.testing.isolation import isolate_ros_graph

# Wall time an awaited event or call may take before the test fails, in s: a net for a hang, not
# a speed limit (SimulatedWorld's CALL_TIMEOUT; this module stays free of ROS imports).
EVENT_TIMEOUT = 30.0
# Wall time after which an idempotent call that got no answer is sent again, in s. A server in a
# program just started can take a request before it has matched the caller's response reader;
# the answer is then dropped (Fast DDS: 'client will not receive response'), and a client that
# only waits, waits for ever.
RESEND_PERIOD = 2.0

# Before rclpy (and any node a test starts) reads the environment.
isolate_ros_graph()
# Messages check the types of the values written into them: an int in a float64 field would
# otherwise be serialised as garbage on some Python versions (seen with 3.12).
os.environ['ROS_PYTHON_CHECK_FIELDS'] = '1'


def pytest_configure(config):
    """Register the markers the suite uses."""
    config.addinivalue_line('markers', 'flake8: code style check')
    config.addinivalue_line('markers', 'pep257: docstring style check')
    config.addinivalue_line('markers', 'linter: static check, not behaviour')
    config.addinivalue_line('markers', 'ros: needs rclpy and the built srv_interfaces')
    config.addinivalue_line('markers', 'long: takes tens of seconds; collected first')


def pytest_collection_modifyitems(items):
    """
    Put the long tests first, in their order, the others after them in theirs.

    The workers of pytest -n take the tests in this order: each long one starts at once on a
    worker of its own while the short ones fill the others, and the workers end together.
    """
    items.sort(key=lambda item: item.get_closest_marker('long') is None)


@pytest.fixture(scope='session')
def rclpy_session():
    """Initialise rclpy once for the whole session on the claimed domain."""
    import rclpy
    rclpy.init()
    yield rclpy
    rclpy.try_shutdown()


class RosHarness:
    """
    Nodes spinning on real executors in background threads, plus a client node.

    Each node gets its own single-threaded executor and thread, as if it ran in a process of
    its own, so a node's callbacks keep the ordering they have under `ros2 run`. The client node
    spins on a SettlingExecutor, as the testing fixture's test nodes do: settle() returns once
    it has handled what came to it, so that after a paused world's steps (RunningWorld.step)
    what the steps sent is in the client's lists.
    """

    def __init__(self):
        from rclpy.node import Node
        self._spinning = []
        self._action_clients = []
        self.client_node = self.add_node(Node('test_client'), settling=True)

    def add_node(self, node, *, settling=False):
        """
        Spin a node on an executor of its own; it is destroyed after the test.

        settling: on a SettlingExecutor, which settle() waits for (the client node); otherwise
        on a single-threaded executor, as `ros2 run` spins the world and the lesson's servers
        (a StoppableExecutor: one that stops spinning before it is shut down).
        """
        from service_tutorial.testing.settling_executor import SettlingExecutor
        from service_tutorial.testing.settling_executor import StoppableExecutor
        executor = (SettlingExecutor(context=node.context) if settling
                    else StoppableExecutor(context=node.context))
        executor.add_node(node)
        thread = threading.Thread(target=executor.spin, daemon=True)
        thread.start()
        self._spinning.append((node, executor, thread))
        return node

    def settle(self, timeout=EVENT_TIMEOUT):
        """Wait until the settling nodes have run every callback ready, and what followed."""
        from service_tutorial.testing.settling_executor import SettlingExecutor
        for node, executor, _ in self._spinning:
            if isinstance(executor, SettlingExecutor):
                assert executor.settle(timeout), \
                    f'node {node.get_name()} kept running callbacks for {timeout} s'

    def destroy(self, entity):
        """
        Destroy a subscription, publisher or client of the client node, on its executor's thread.

        Destroyed from the test's thread, an entity with event handlers can be taken apart while
        the executor puts it in its wait set, which kills the executor (rclpy's InvalidHandle):
        the client node then hears nothing more.
        """
        from rclpy.client import Client
        from rclpy.publisher import Publisher
        from rclpy.subscription import Subscription
        node, executor, _ = self._spinning[0]
        destroy = {Subscription: node.destroy_subscription, Publisher: node.destroy_publisher,
                   Client: node.destroy_client}[type(entity)]
        task = executor.create_task(destroy, entity)
        assert self.wait_for(task.done), 'the client node did not destroy it'
        task.result()

    def action_client(self, action_type, action_name):
        """Make an action client on the client node; it is destroyed after the test."""
        from service_tutorial.lesson.goal_client import GoalClient
        client = GoalClient(self.client_node, action_type, action_name)
        self._action_clients.append(client)
        return client

    def call(self, srv_type, service_name, request, *, timeout=EVENT_TIMEOUT, idempotent=False):
        """
        Call a service from the client node and return its response or fail the test.

        idempotent: asking twice does what asking once does (a query, setting a value), so the
        request is sent again each RESEND_PERIOD s without an answer: its answer may be lost.
        """
        client = self.client_node.create_client(srv_type, service_name)
        try:
            assert client.wait_for_service(timeout_sec=timeout), \
                f'service {service_name} did not appear within {timeout} s'
            deadline = time.monotonic() + timeout
            futures = [client.call_async(request)]

            def answered():
                return any(future.done() for future in futures)
            while not self.wait_for(answered, timeout=min(
                    RESEND_PERIOD if idempotent else timeout, deadline - time.monotonic())):
                assert time.monotonic() < deadline, \
                    f'service {service_name} did not answer within {timeout} s'
                futures.append(client.call_async(request))
            return next(future for future in futures if future.done()).result()
        finally:
            self.destroy(client)

    def subscribe(self, msg_type, topic, *, depth=100):
        """Collect every message on a topic into a list that grows while the test runs."""
        received = []
        self.client_node.create_subscription(msg_type, topic, received.append, depth)
        return received

    def receive(self, msg_type, topic, *, count=1, timeout=30.0):
        """Subscribe to a topic until count messages came, then unsubscribe; return them."""
        received = []
        subscription = self.client_node.create_subscription(
            msg_type, topic, received.append, 10)
        try:
            assert self.wait_for(lambda: len(received) >= count, timeout=timeout), \
                f'{len(received)} of {count} messages on {topic} within {timeout} s'
        finally:
            self.destroy(subscription)
        return received

    def set_parameter(self, node_name, name, value):
        """Set one parameter through a node's set_parameters service, as `ros2 param set` does."""
        from rcl_interfaces.msg import Parameter as ParameterMsg, ParameterValue
        from rcl_interfaces.srv import SetParameters
        from rclpy.parameter import Parameter
        if not isinstance(value, ParameterValue):
            value = Parameter(name, value=value).get_parameter_value()
        request = SetParameters.Request(parameters=[ParameterMsg(name=name, value=value)])
        return self.call(SetParameters, f'/{node_name}/set_parameters', request,
                         idempotent=True).results[0]

    def get_parameter(self, node_name, name):
        """Return one parameter's value from a node's get_parameters service."""
        from rcl_interfaces.srv import GetParameters
        request = GetParameters.Request(names=[name])
        return self.call(GetParameters, f'/{node_name}/get_parameters', request,
                         idempotent=True).values[0]

    def start_world(self, **parameters):
        """Start the world node with these parameters; return it once its first /clock came."""
        from running_world import RunningWorld
        return RunningWorld(self, **parameters)

    @staticmethod
    def wait_for(predicate, *, timeout=EVENT_TIMEOUT, period=0.002):
        """Wait until predicate() is true; return whether it became true in time."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(period)
        return bool(predicate())

    def shutdown(self):
        """
        Stop every executor and destroy every action client and node the test used.

        A node that stays in the graph after destroy_node() is still held by something (an
        ActionServer that was not destroyed keeps its node alive): the test fails, as the
        node would go on answering the tests that come after it.
        """
        for client in self._action_clients:
            client.destroy()
        client_node = self.client_node
        listed = client_node.get_node_names_and_namespaces
        before = listed()
        destroyed = []  # (name, namespace) of each node of the client's context destroyed
        for node, executor, thread in reversed(self._spinning):
            executor.stop()
            thread.join(timeout=5.0)
            executor.shutdown(timeout_sec=5.0)
            if node is not client_node:
                if node.context is client_node.context:
                    destroyed.append((node.get_name(), node.get_namespace()))
                node.destroy_node()

        def left_behind():
            now = listed()
            return sorted(name for name in set(destroyed)
                          if now.count(name) > before.count(name) - destroyed.count(name))
        try:
            assert self.wait_for(lambda: not left_behind()), \
                f'nodes still in the graph after destroy_node(): {left_behind()}'
        finally:
            client_node.destroy_node()


@pytest.fixture
def ros(rclpy_session):
    """Give a test a spinning executor and a client node, torn down afterwards."""
    harness = RosHarness()
    yield harness
    harness.shutdown()


@pytest.fixture(scope='class')
def class_ros(rclpy_session):
    """Give the tests of a class one harness, for a world they share."""
    harness = RosHarness()
    yield harness
    harness.shutdown()


@pytest.fixture
def paused_world(ros):
    """Start the default world paused: time moves only by its step(n), in whole steps."""
    return ros.start_world(paused=True)


@pytest.fixture
def fast_world(ros):
    """Start the default world free-running, as fast as the machine can."""
    return ros.start_world(real_time_factor=0.0)


@pytest.fixture
def real_time_world(ros):
    """Start the default world in real time, for driving with cmd_vel at a human pace."""
    return ros.start_world(real_time_factor=1.0)


@pytest.fixture
def start_program():
    """Start programs with piped output; any still running when the test ends is killed."""
    started = []

    def start(command, **options):
        process = subprocess.Popen(command, **{
            'stdout': subprocess.PIPE, 'stderr': subprocess.PIPE, 'text': True, **options})
        started.append(process)
        return process
    yield start
    for process in started:
        if process.poll() is None:
            process.kill()
        process.wait()
        for stream in (process.stdin, process.stdout, process.stderr):
            if stream is not None:
                stream.close()
