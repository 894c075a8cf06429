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
    """Tells whether one of its publishers has subscribers; asks every SUBSCRIBER_CHECK_PERIOD."""

    def __init__(self, *publishers, wall_clock=time.monotonic):
        """Watch rclpy publishers (add() watches more); the first question asks at once."""
        self.publishers = list(publishers)
        self.next_look = -math.inf  # wall time at which listened() asks again
        self._wall_clock = wall_clock
        self._listened = False

    def add(self, publisher):
        """Watch one more publisher, from the next question on."""
        self.publishers.append(publisher)

    def listened(self):
        """Tell whether a publisher had a subscriber when last asked."""
        wall = self._wall_clock()
        if wall >= self.next_look:
            self.next_look = wall + SUBSCRIBER_CHECK_PERIOD
            self._listened = any(publisher.get_subscription_count() > 0
                                 for publisher in self.publishers)
        return self._listened
