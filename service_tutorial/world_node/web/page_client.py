"""
The page as one more ROS client of the world: its own small node, spun on a thread of its own.

viser runs the page's callbacks on its own threads, which must never touch the world. They
call PageClient instead, which sends the very requests a ROS client would (the world's
services, /control_robot_angle, a Twist on cmd_vel) and hands each answer to a callback on the
client's executor thread. One call of each kind at a time: a click that comes while the last
one of its kind is still unanswered is dropped, and the caller is told so. It also subscribes
to the sensor topics the page shows (listen()), as raw bytes it never reads: the page draws
the sensors' readings from the world, and only needs them to measure.
"""

import threading

from geometry_msgs.msg import Twist
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from service_tutorial.conversions import make_pose
from srv_interfaces.srv import ControlTurningMessage, DeleteModel, GetModelList, SpawnModel
from std_srvs.srv import Empty

# The lesson's R2-D2: where its spawn_model_client puts it, turned -90 degrees about z.
R2D2_NAME = 'r2d2'
R2D2_POSITION = (-2.0, 1.0, 1.0)
R2D2_QUATERNION = (0.0, 0.0, -0.707, 0.707)  # x, y, z, w
# A drive button is a teleop's key held for this long: its Twist is sent again every period,
# so the world's cmd_vel_timeout does not stop the robot while the command stands.
DRIVE_HOLD = 1.0  # s
DRIVE_PERIOD = 0.1  # s
CMD_VEL_DEPTH = 10
SENSOR_DEPTH = 1
SPIN_PERIOD = 0.1  # s: how soon the client's thread sees close()


class PageClient:
    """Calls the world's services and drives the robot for the page, off the page's threads."""

    def __init__(self, world_node):
        """Make the page's node beside world_node, in its namespace, and start spinning it."""
        self.node = Node('mujoco_web', namespace=world_node.get_namespace(),
                         context=world_node.context, start_parameter_services=False)
        node, world = self.node, world_node.get_name()
        # Relative names: the page's node shares the world's namespace, so these are exactly
        # the world's ~/ services, the turning server's service and tinybot's cmd_vel there.
        self.clients = {
            'spawn': node.create_client(SpawnModel, f'{world}/spawn_urdf_model'),
            'delete': node.create_client(DeleteModel, f'{world}/delete_model'),
            'reset': node.create_client(Empty, f'{world}/reset_simulation'),
            'pause': node.create_client(Empty, f'{world}/pause_physics'),
            'resume': node.create_client(Empty, f'{world}/unpause_physics'),
            'model_list': node.create_client(GetModelList, f'{world}/get_model_list'),
            'turn': node.create_client(ControlTurningMessage, 'control_robot_angle'),
        }
        self.cmd_vel_pub = node.create_publisher(Twist, 'cmd_vel', CMD_VEL_DEPTH)
        self._drive = Twist()
        self._drive_until = 0.0
        self.drive_timer = node.create_timer(DRIVE_PERIOD, self.drive_timer_callback)
        self.drive_timer.cancel()
        self._in_flight = set()
        self.subscriptions = {}  # topic -> raw subscription, for the sensors shown
        self._lock = threading.Lock()
        self.sent_calls = 0  # requests sent for the page
        self.dropped_calls = 0  # clicks dropped while a call of their kind was unanswered
        self._stopping = threading.Event()
        self.executor = SingleThreadedExecutor(context=world_node.context)
        self.executor.add_node(node)
        self._thread = threading.Thread(target=self._spin, name='web page client', daemon=True)
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

    def spawn_r2d2(self, urdf, answered):
        """Ask the world to spawn R2-D2 where the lesson does."""
        request = SpawnModel.Request(model_name=R2D2_NAME, model_xml=urdf)
        request.initial_pose = make_pose(*R2D2_POSITION, quaternion=R2D2_QUATERNION)
        return self.call('spawn', request, answered)

    def delete_r2d2(self, answered):
        """Ask the world to delete R2-D2."""
        return self.call('delete', DeleteModel.Request(model_name=R2D2_NAME), answered)

    def turn(self, time_duration, angular_vel, answered):
        """Ask /control_robot_angle for a turn already checked against the lesson's limits."""
        request = ControlTurningMessage.Request(time_duration=time_duration,
                                                angular_vel=angular_vel)
        return self.call('turn', request, answered)

    def drive(self, linear, angular):
        """Send a Twist on cmd_vel now and for DRIVE_HOLD seconds; (0, 0) stops at once."""
        twist = Twist()
        twist.linear.x, twist.angular.z = float(linear), float(angular)
        with self._lock:
            self._drive = twist
            self._drive_until = self.node.get_clock().now().nanoseconds * 1e-9 + DRIVE_HOLD
        self.cmd_vel_pub.publish(twist)
        if linear or angular:
            self.drive_timer.reset()
        else:
            self.drive_timer.cancel()

    def drive_timer_callback(self):
        """Send the standing drive command again, until it has been held DRIVE_HOLD s."""
        with self._lock:
            twist, until = self._drive, self._drive_until
        if self.node.get_clock().now().nanoseconds * 1e-9 >= until:
            self.drive_timer.cancel()
            return
        self.cmd_vel_pub.publish(twist)

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
        self._thread.join(timeout=2.0)
        self.executor.shutdown()
        self.node.destroy_node()


def _ignore(_serialized):
    """Take a sensor message and drop it: the page shows the reading from the world."""
