"""
An action client that may send from one thread while its node spins on another.

rclpy's ActionClient (Jazzy) sends a request and only then files the future that is to take its
answer. When the node spins on another thread, the answer can be taken in between: it is then
dropped ('Ignoring unexpected goal response') and the future never completes, so a client
that waits for it waits for ever (ros2/rclpy#1123). GoalClient sends and files under one lock,
and looks an answer up only once no request is half filed.
"""

import threading

from rclpy.action import ActionClient


class GoalClient(ActionClient):
    """An ActionClient whose goal, cancel and result requests always get their answers."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._sending = threading.Lock()

    def send_goal_async(self, *args, **kwargs):
        """Send a goal (as ActionClient does); its answer completes the future returned."""
        with self._sending:
            return super().send_goal_async(*args, **kwargs)

    def _cancel_goal_async(self, goal_handle):
        with self._sending:
            return super()._cancel_goal_async(goal_handle)

    def _get_result_async(self, goal_handle):
        with self._sending:
            return super()._get_result_async(goal_handle)

    async def execute(self, taken_data):
        """Hand the answers taken to their futures, once a request being sent is filed."""
        if taken_data.keys() & {'goal', 'cancel', 'result'}:
            with self._sending:
                pass
        return await super().execute(taken_data)
