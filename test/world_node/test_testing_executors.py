"""The test executors stop spinning on request, so that shutting them down races nothing."""

import threading

import pytest
from rclpy.node import Node
from service_tutorial.testing.settling_executor import SettlingExecutor, StoppableExecutor

pytestmark = pytest.mark.ros


@pytest.fixture
def thread_errors():
    """Collect what any thread raises during the test (threading.excepthook)."""
    errors = []
    previous = threading.excepthook
    threading.excepthook = errors.append
    yield errors
    threading.excepthook = previous


@pytest.mark.parametrize('executor_type', [StoppableExecutor, SettlingExecutor])
def test_a_stopped_executor_leaves_its_thread_and_shuts_down_cleanly(
        rclpy_session, thread_errors, executor_type):
    node = Node('executor_under_test')
    ran = threading.Semaphore(0)
    # Its only entity besides the node's own services: nothing wakes the executor by itself.
    guard = node.create_guard_condition(ran.release)
    executor = executor_type(context=node.context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    for _ in range(3):  # it spins: each trigger's callback runs
        guard.trigger()
        assert ran.acquire(timeout=10.0), 'the executor ran no callback'

    executor.stop()
    thread.join(timeout=10.0)
    assert not thread.is_alive(), 'the spinning thread did not end on stop()'
    assert executor.shutdown(timeout_sec=10.0)
    node.destroy_node()
    assert thread_errors == []
