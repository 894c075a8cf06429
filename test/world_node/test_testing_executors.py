"""The test executors: they stop spinning on request, and settle beside awaiting callbacks."""

import threading

import pytest
from rclpy.callback_groups import ReentrantCallbackGroup
from rclpy.node import Node
from rclpy.task import Future
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


def test_a_callback_awaiting_a_future_settles_and_goes_on_once_it_is_done(rclpy_session):
    # The shape of an action server's execute callback, or the turning server's: a coroutine
    # that awaits what later callbacks bring. Awaiting, its node has settled; it goes on, and
    # the executor settles again, once another callback ends what it awaits.
    node = Node('awaiting_node')
    gate = Future()
    steps = []

    async def waits_for_the_gate():
        steps.append('began')
        steps.append(await gate)

    # Reentrant, as such a callback's group must be: it stays in its group while it awaits.
    begin = node.create_guard_condition(waits_for_the_gate,
                                        callback_group=ReentrantCallbackGroup())
    open_gate = node.create_guard_condition(lambda: gate.set_result('went on'))
    executor = SettlingExecutor(context=node.context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    try:
        begin.trigger()
        assert executor.settle(10.0), 'a callback awaiting a future kept the node unsettled'
        assert steps == ['began']
        open_gate.trigger()
        assert executor.settle(10.0)
        assert steps == ['began', 'went on']
    finally:
        executor.stop()
        thread.join(timeout=10.0)
        executor.shutdown(timeout_sec=10.0)
        node.destroy_node()
