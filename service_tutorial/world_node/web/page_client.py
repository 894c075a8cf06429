"""
The page as one more ROS client of the world: its own small node, spun on a thread of its own.

viser runs the page's callbacks on its own threads, which must never touch the world. A panel's
buttons call PageClient instead, which sends the very requests a ROS client would and hands
each answer to a callback on the client's executor thread. One call of each kind at a time: a
click that comes while the last one of its kind is still unanswered is dropped, and the caller
is told so. It also subscribes to the sensor topics the page shows (listen()), as raw bytes it
never reads: the page draws the sensors' readings from the world, and only needs them to
measure.

The world's own page has no buttons, so this client calls nothing by itself. A panel
contributed to the page (panel.py) names a subclass as its client_type, which adds the service
clients and publishers its buttons need (add_call()) before the page starts the client.
"""

import threading

from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node

SENSOR_DEPTH = 1
SPIN_PERIOD = 0.1  # s: how soon the client's thread sees close()


class PageClient:
    """Calls services and listens to sensors for the page, off the page's threads."""

    def __init__(self, world_node):
        """Make the page's node beside world_node, in its namespace; start() spins it."""
        self.node = Node('mujoco_web', namespace=world_node.get_namespace(),
                         context=world_node.context, start_parameter_services=False)
        # The page's node shares the world's namespace: a relative name f'{world_name}/...'
        # is exactly one of the world's ~/ services.
        self.world_name = world_node.get_name()
        self.clients = {}  # kind of call -> service client
        self._in_flight = set()
        self.subscriptions = {}  # topic -> raw subscription, for the sensors shown
        self._lock = threading.Lock()
        self.sent_calls = 0  # requests sent for the page
        self.dropped_calls = 0  # clicks dropped while a call of their kind was unanswered
        self._stopping = threading.Event()
        self.executor = SingleThreadedExecutor(context=world_node.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name='web page client', daemon=True)

    def add_call(self, kind, srv_type, srv_name):
        """Make the client of a kind of call ('spawn', 'turn', ...); a relative name is kept."""
        self.clients[kind] = self.node.create_client(srv_type, srv_name)

    def start(self):
        """Start spinning the page's node on a thread of its own."""
        self._thread.start()

    def _spin(self):
        # Until close() says stop; the executor is shut down only once this thread has ended
        # (shut down from another thread while it waits, rclpy's executor can trip over it).
        try:
            while not self._stopping.is_set():
                self.executor.spin_once(timeout_sec=SPIN_PERIOD)
        except ExternalShutdownException:
            pass

    def service_name(self, kind):
        """Return the full name of the service a kind of call goes to."""
        return self.node.resolve_service_name(self.clients[kind].srv_name)

    def call(self, kind, request, answered):
        """
        Send a request of a kind ('spawn', 'turn', ...) and return True, or False if dropped.

        answered(response) runs on the client's thread once the answer comes, or
        answered(None) at once if the service is not there.
        """
        with self._lock:
            if kind in self._in_flight:
                self.dropped_calls += 1
                return False
            self._in_flight.add(kind)
            self.sent_calls += 1
        client = self.clients[kind]
        if not client.service_is_ready():
            self._finished(kind)
            answered(None)
            return True
        future = client.call_async(request)

        def done(future):
            self._finished(kind)
            answered(future.result())
        future.add_done_callback(done)
        return True

    def _finished(self, kind):
        with self._lock:
            self._in_flight.discard(kind)

    def listen(self, wanted):
        """Subscribe to exactly the topics of wanted, {topic: message type}."""
        for topic in [topic for topic in self.subscriptions if topic not in wanted]:
            self.node.destroy_subscription(self.subscriptions.pop(topic))
        for topic, msg_type in wanted.items():
            if topic not in self.subscriptions:
                self.subscriptions[topic] = self.node.create_subscription(
                    msg_type, topic, _ignore, SENSOR_DEPTH, raw=True)

    def close(self):
        """Stop spinning and destroy the page's node."""
        self._stopping.set()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.executor.shutdown()
        self.node.destroy_node()


def _ignore(_serialized):
    """Take a sensor message and drop it: the page shows the reading from the world."""
