"""
Subscriptions that the world node reads at each tick, not its executor: every robot's cmd_vel.

rclpy's executor rebuilds its wait set in Python each time it wakes, at a cost that grows
with the node's subscriptions and services, and a message that arrives on its own wakes it
once. A fleet of 50 robots, each commanded twice a second, woke the world 100 times a second
more, and its 50 cmd_vel subscriptions were most of every wait set. A velocity command only
takes effect at the next step anyway (the callback stores it, as turtlesim's does), so the
world node takes these messages itself at the start of each tick, oldest first.
"""

from rclpy.callback_groups import CallbackGroup


class TakenAtTick(CallbackGroup):
    """A callback group the executor never waits on: the node calls take_messages() instead."""

    def can_execute(self, entity):
        """Never: the executor leaves the group's entities out of its wait set."""
        return False

    def beginning_execution(self, entity):
        """Never: see can_execute()."""
        return False

    def ending_execution(self, entity):
        """Nothing was begun."""


def take_messages(subscription):
    """Return the messages waiting on a subscription of a TakenAtTick group, oldest first."""
    messages = []
    handle = subscription.handle
    with handle:
        while True:
            taken = handle.take_message(subscription.msg_type, subscription.raw)
            if taken is None:
                return messages
            messages.append(taken[0])
