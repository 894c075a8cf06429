"""
Whether anyone listens to a topic, asked of the middleware a few times per wall second.

The world node builds and publishes nothing for a topic nobody subscribes to. rclpy answers
get_subscription_count() in a few microseconds, but a fleet's odometry, joint states and /tf
asked it thousands of times per second. A SubscriberWatch asks once per
SUBSCRIBER_CHECK_PERIOD of wall time: a new subscriber's first message may come that much
later, about as long as discovery takes anyway.
"""

import math
import time

SUBSCRIBER_CHECK_PERIOD = 0.2  # s of wall time between two looks for subscribers


class SubscriberWatch:
    """Tells whether a publisher has subscribers, asking again every SUBSCRIBER_CHECK_PERIOD."""

    def __init__(self, publisher, *, wall_clock=time.monotonic):
        """Watch an rclpy publisher; the first question asks at once."""
        self.publisher = publisher
        self._wall_clock = wall_clock
        self._next_look = -math.inf
        self._listened = False

    def listened(self):
        """Tell whether the publisher had a subscriber when last asked."""
        wall = self._wall_clock()
        if wall >= self._next_look:
            self._next_look = wall + SUBSCRIBER_CHECK_PERIOD
            self._listened = self.publisher.get_subscription_count() > 0
        return self._listened
