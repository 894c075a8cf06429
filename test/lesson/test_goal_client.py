"""
GoalClient: every answer of an action server reaches its future, whichever thread sent.

The lesson's action client sends from its main thread while its node spins on another. Here
each request is held back after it is sent until its answer has been taken by the spinning
thread: the order in which rclpy's own ActionClient drops the answer and waits for ever.
"""

import threading

import pytest
from rclpy.action import ActionServer, CancelResponse
from rclpy.node import Node
from rclpy.task import Future
from service_tutorial.lesson.goal_client import GoalClient
from srv_interfaces.action import TurnRobot

pytestmark = pytest.mark.ros
# Wall time a held-back request waits for its answer to be taken: a net for a hang.
EVENT_TIMEOUT = 30.0


class AnswerFirst:
    """A client's rcl handle whose requests return only once their answers have been taken."""

    KINDS = {'send_goal_request': 'take_goal_response',
             'send_cancel_request': 'take_cancel_response',
             'send_result_request': 'take_result_response'}

    def __init__(self, handle, held):
        self._handle = handle
        self._held = held  # the requests to hold back: send_goal_request, ...
        self._taken = {take: threading.Event() for take in self.KINDS.values()}
        self.held_back = []  # the requests sent that returned after their answer was taken

    def __getattr__(self, name):
        if name in self._held:
            return lambda request: self._send(name, request)
        if name in self._taken:
            return lambda response_type: self._take(name, response_type)
        return getattr(self._handle, name)

    def _send(self, send, request):
        taken = self._taken[self.KINDS[send]]
        taken.clear()
        sequence_number = getattr(self._handle, send)(request)
        assert taken.wait(EVENT_TIMEOUT), f'no answer taken to {send}'
        self.held_back.append(send)
        return sequence_number

    def _take(self, take, response_type):
        answer = getattr(self._handle, take)(response_type)
        if all(answer):
            self._taken[take].set()
        return answer


class Turner(Node):
    """A turn_robot server: a goal of angle 0 succeeds at once, any other waits to be cancelled."""

    def __init__(self):
        super().__init__('goal_client_test_server')
        self.cancelled = Future()
        self.server = ActionServer(self, TurnRobot, '/turn_robot', self.execute,
                                   cancel_callback=self.cancel)

    def destroy_node(self):
        """Take the action server along: left behind, it would serve turn_robot to later tests."""
        self.server.destroy()
        return super().destroy_node()

    def cancel(self, goal_handle):
        self.cancelled.set_result(True)
        return CancelResponse.ACCEPT

    async def execute(self, goal_handle):
        if goal_handle.request.angle != 0.0:
            await self.cancelled
            goal_handle.canceled()
            return TurnRobot.Result(message='canceled')
        goal_handle.succeed()
        return TurnRobot.Result(success=True, message='reached')


def answering_first(ros, *held):
    """Start the server; return a GoalClient of it that holds back the requests held."""
    ros.add_node(Turner())
    client = ros.action_client(TurnRobot, '/turn_robot')
    assert isinstance(client, GoalClient)
    client._client_handle = AnswerFirst(client._client_handle, held)
    assert client.wait_for_server(timeout_sec=EVENT_TIMEOUT)
    return client


def answer(ros, future):
    assert ros.wait_for(future.done), 'the answer taken never reached its future'
    return future.result()


def test_a_goal_and_its_result_answered_before_they_are_filed_arrive(ros):
    client = answering_first(ros, 'send_goal_request', 'send_result_request')
    goal = answer(ros, client.send_goal_async(TurnRobot.Goal(angle=0.0, angular_vel=0.5)))
    assert goal.accepted
    result = answer(ros, goal.get_result_async()).result

    assert result.success and result.message == 'reached'
    assert client._client_handle.held_back == ['send_goal_request', 'send_result_request']


def test_a_cancel_answered_before_it_is_filed_arrives(ros):
    # The result is not held back: it comes only once the goal is cancelled.
    client = answering_first(ros, 'send_goal_request', 'send_cancel_request')
    goal = answer(ros, client.send_goal_async(TurnRobot.Goal(angle=1.0, angular_vel=0.5)))
    result = goal.get_result_async()
    cancel = answer(ros, goal.cancel_goal_async())

    assert len(cancel.goals_canceling) == 1
    assert answer(ros, result).result.message == 'canceled'
    assert client._client_handle.held_back == ['send_goal_request', 'send_cancel_request']
