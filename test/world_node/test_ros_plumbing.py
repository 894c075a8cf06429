"""The world node's topic plumbing: subscriber watches and commands taken at each tick."""

from geometry_msgs.msg import Twist, Vector3
from rclpy.node import Node
from service_tutorial.world_node.subscribers import SUBSCRIBER_CHECK_PERIOD, SubscriberWatch
from service_tutorial.world_node.taken_at_tick import take_messages, TakenAtTick


class CountingPublisher:
    """Answers get_subscription_count() with a number the test sets, and counts the asks."""

    def __init__(self):
        self.subscribers = 0
        self.asked = 0

    def get_subscription_count(self):
        self.asked += 1
        return self.subscribers


def test_a_watch_asks_once_per_period_and_sees_a_subscriber_come_and_go():
    wall = [100.0]  # a wall clock that stands still until the test moves it
    publisher = CountingPublisher()
    watch = SubscriberWatch(publisher, wall_clock=lambda: wall[0])
    assert not watch.listened() and publisher.asked == 1
    publisher.subscribers = 1
    for _ in range(100):
        assert not watch.listened(), 'the answer holds until the period is over'
    assert publisher.asked == 1
    wall[0] += SUBSCRIBER_CHECK_PERIOD
    assert watch.listened() and publisher.asked == 2
    publisher.subscribers = 0
    wall[0] += SUBSCRIBER_CHECK_PERIOD
    assert not watch.listened() and publisher.asked == 3


def test_commands_taken_at_tick_never_reach_the_executor_and_keep_their_order(ros):
    world_side = ros.add_node(Node('taken_at_tick_world'))
    served = []
    subscription = world_side.create_subscription(
        Twist, 'taken_at_tick_cmd_vel', served.append, 10, callback_group=TakenAtTick())
    publisher = ros.client_node.create_publisher(Twist, 'taken_at_tick_cmd_vel', 10)
    assert ros.wait_for(lambda: publisher.get_subscription_count() > 0)
    for speed in (0.1, 0.2, 0.3):
        publisher.publish(Twist(linear=Vector3(x=speed)))
    taken = []
    # The executor spins all along (ros.wait_for); had it served the subscription, its
    # callback would have had the messages and nothing would be left to take.
    assert ros.wait_for(lambda: taken.extend(take_messages(subscription)) or len(taken) == 3)
    assert [msg.linear.x for msg in taken] == [0.1, 0.2, 0.3]
    assert served == []
    assert take_messages(subscription) == []


def test_a_watch_of_several_publishers_sees_a_subscriber_on_any_of_them():
    image, info = CountingPublisher(), CountingPublisher()
    wall = [0.0]
    watch = SubscriberWatch(image, wall_clock=lambda: wall[0])
    watch.add(info)
    assert not watch.listened()
    info.subscribers = 1
    wall[0] += SUBSCRIBER_CHECK_PERIOD
    assert watch.listened() and watch.next_look == wall[0] + SUBSCRIBER_CHECK_PERIOD
