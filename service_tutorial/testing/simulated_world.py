"""
A world for a user's test: the world node started paused on a ROS graph of its own.

SimulatedWorld runs the world node (MujocoWorld) in this process, on an rclpy Context of its
own whose ROS domain no other run on this machine holds, with discovery kept on localhost: the
test's nodes see the world and nothing else does. Its own Context lets it sit beside a test
suite that has called rclpy.init() already, or one that never does. Time moves only when the
test says step(n): the world answers once it has taken exactly n steps, and step() returns once
/clock says so and the test's own nodes (add_node) have handled what the steps sent them, so
what a test asserts does not depend on how fast the machine is.

The standard's services (simulation_interfaces) are reached by names relative to the world's
namespace, through typed helpers for the common ones and call() for any other; a helper raises
SimulationCallError when the world refuses, with the world's code and message.
"""

import operator
import threading
import time

import rclpy
from rclpy.context import Context
from rclpy.duration import Duration
from rclpy.node import Node
from rclpy.parameter import Parameter
from rclpy.qos import DurabilityPolicy, qos_check_compatible, QoSCompatibility, QoSProfile
from rclpy.qos import ReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from rosgraph_msgs.msg import Clock
from service_tutorial.conversions import make_pose, NANOSECONDS
from service_tutorial.testing.isolation import claim_ros_domain, localhost_discovery
from service_tutorial.testing.settling_executor import SettlingExecutor
from service_tutorial.testing.settling_executor import StoppableExecutor
from service_tutorial.world_node.pacing import PAUSED_TICK_PERIOD
from service_tutorial.world_node.subscribers import SUBSCRIBER_CHECK_PERIOD
from simulation_interfaces.msg import EntityFilters, EntityState, Result, SimulationState
from simulation_interfaces.srv import DeleteEntity, GetEntities, GetEntityState
from simulation_interfaces.srv import GetSimulationState, ResetSimulation, SetEntityState
from simulation_interfaces.srv import SetSimulationState, SpawnEntity, StepSimulation

# Wall time a service call or an awaited event may take before the test fails, in s: a net for a
# world that hangs, not a speed limit. 10 s failed a world start on a machine with both cores
# burnt beside three test workers.
CALL_TIMEOUT = 30.0
# Wall time each step asked for may add to that, in s: worlds whose sensors cast and render at
# every step, on a machine as busy, took more than 20 ms a step.
STEP_TIMEOUT = 0.05
# Wall time the world may take to start (imports, models, discovery), in s.
START_TIMEOUT = 60.0
# /clock as the world publishes it: the latest time, kept for a late subscriber.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)


class SimulationCallError(RuntimeError):
    """A standard service of the world answered with another result than RESULT_OK."""

    def __init__(self, service, result):
        super().__init__(f'{service} answered result {result.result}: {result.error_message}')
        self.service = service
        self.code = result.result
        self.message = result.error_message


def pose_of(pose):
    """Return a geometry_msgs/Pose given as one, or as (x, y, z) or (x, y, z, yaw)."""
    if pose is None:
        return make_pose()
    if hasattr(pose, 'position'):
        return pose
    try:
        values = [float(value) for value in pose]
    except (TypeError, ValueError):
        values = []
    if len(values) not in (3, 4):
        raise ValueError(f'a pose is a Pose, (x, y, z) or (x, y, z, yaw): {pose!r}')
    return make_pose(*values[:3], yaw=values[3] if len(values) == 4 else None)


def whole_steps(steps):
    """Return a count of steps as an int, or raise ValueError naming what was given."""
    try:
        count = operator.index(steps)  # 3 and numpy's int64(3), not 3.0
    except TypeError:
        count = None
    if count is None or isinstance(steps, bool) or count < 1:
        raise ValueError(f'steps must be a whole number of at least 1: {steps!r}')
    return count


class SimulatedWorld:
    """The world node, paused on a graph of its own, with the standard's calls and step(n)."""

    def __init__(self, *, namespace='/', **parameters):
        """Start the world with these parameters (paused unless paused=False is given)."""
        # Imported here: the world's simulation imports take a while, and only a test needs them.
        from service_tutorial.world_node.node import MujocoWorld
        self.namespace = '/' + namespace.strip('/')
        self._claim = claim_ros_domain()
        self.context = Context()
        self._spinning = []  # (node, executor, thread), in the order they started
        self._added = []  # (node, executor) of the test's own nodes
        self._clients = {}
        self._time_ns = None
        self._heard_subscribers = {}  # topic of the world -> its subscribers at the last step
        self._clock_changed = threading.Condition()
        try:
            with localhost_discovery():
                rclpy.init(context=self.context, domain_id=self._claim.domain_id,
                           signal_handler_options=SignalHandlerOptions.NO)
            # In a context of its own, the world publishes its sensors' topics from its own
            # participant too (world_node/participants.py): the domain's one participant here,
            # with the test's nodes (add_node), which goes with close() beside no neighbour.
            self.world_node = self._spin(MujocoWorld(
                context=self.context, namespace=self.namespace,
                parameter_overrides=[Parameter(name, value=value) for name, value in
                                     {'paused': True, **parameters}.items()]))
            self.node = self._spin(Node('simulation_test_client', context=self.context))
            self._clock_sub = self.node.create_subscription(
                Clock, '/clock', self._clock_callback, CLOCK_QOS)
            self._wait_for_clock(lambda now: True, START_TIMEOUT)
            # Nothing was published to them yet: the world asks afresh at the first steps.
            self._heard_subscribers = {publisher.topic_name: publisher.get_subscription_count()
                                       for publisher in self.world_node.publishers}
        except BaseException:
            self.close()
            raise

    @property
    def domain_id(self):
        """Return the ROS domain id of this world's graph."""
        return self._claim.domain_id

    @property
    def timestep(self):
        """Return the physics step of the world loaded, in s (an SDF world may have its own)."""
        return self.world_node.world.timestep

    @property
    def time(self):
        """Return the simulation time, in s, as /clock last said it."""
        return self._time_ns / NANOSECONDS

    # --- nodes --------------------------------------------------------------------------------

    def add_node(self, node):
        """Spin a node of the test on this world's graph until the test ends; return it."""
        if node.context is not self.context:
            raise ValueError(f'node {node.get_fully_qualified_name()} was made in another '
                             'rclpy Context: make it with context=<the world>.context')
        executor = SettlingExecutor(context=self.context)
        self._spin(node, executor)
        self._added.append((node, executor))
        return node

    def _spin(self, node, executor=None):
        """Spin a node on an executor and thread of its own, as if in a process of its own."""
        executor = executor or StoppableExecutor(context=self.context)
        executor.add_node(node)
        thread = threading.Thread(target=executor.spin, daemon=True,
                                  name=f'spin {node.get_name()}')
        thread.start()
        self._spinning.append((node, executor, thread))
        return node

    # --- time ---------------------------------------------------------------------------------

    def step(self, steps=1, *, timeout=None):
        """
        Take exactly steps steps of the paused world; return the simulation time after them.

        What the nodes added with add_node() published before is in the world's hands when
        the steps start: a velocity command acts from the first of them. Returns once the
        world has answered, /clock says so, and every added node has handled what came to it
        (SettlingExecutor.settle()): what the nodes publish in reaction is there for the next
        steps.
        """
        steps = whole_steps(steps)
        timeout = CALL_TIMEOUT + STEP_TIMEOUT * steps if timeout is None else timeout
        self._wait_until_new_subscribers_are_heard()
        self._wait_until_sent_messages_are_received()
        end_ns = self._time_ns + round(steps * self.timestep * NANOSECONDS)
        half_step_ns = round(self.timestep * NANOSECONDS / 2)
        self._ok('step_simulation', self.call(
            StepSimulation, 'step_simulation', StepSimulation.Request(steps=steps),
            timeout=timeout).result)
        self._wait_for_clock(lambda now: now >= end_ns - half_step_ns, timeout)
        for node, executor in self._added:
            assert executor.settle(timeout), \
                f'node {node.get_name()} kept running callbacks for {timeout} s after the steps'
        return self.time

    def _wait_until_new_subscribers_are_heard(self):
        """
        Wait until the world sends its next messages to every subscriber that came since.

        A publisher learns of a subscription a moment after the graph shows it, and the world
        asks whether anyone listens to a topic once per SUBSCRIBER_CHECK_PERIOD of wall time:
        a new subscriber to one of the world's topics waits that long, once, and its first
        message comes with the first steps after it. A sensor switches on when the world looks
        at its watch after that: at the paused world's next tick (PAUSED_TICK_PERIOD apart) at
        least FACE_LOOK_PERIOD after its last look, so the wait is that much longer.
        """
        from service_tutorial.world_node.node import FACE_LOOK_PERIOD
        assert self.wait_for(lambda: not self._unmatched_publishers(), timeout=CALL_TIMEOUT), \
            'publishers that still miss subscribers: ' + ', '.join(
                sorted({publisher.topic_name for publisher in self._unmatched_publishers()}))
        counts = {publisher.topic_name: publisher.get_subscription_count()
                  for publisher in self.world_node.publishers}
        if any(count > self._heard_subscribers.get(topic, 0) for topic, count in counts.items()):
            time.sleep(SUBSCRIBER_CHECK_PERIOD + PAUSED_TICK_PERIOD + FACE_LOOK_PERIOD)
        self._heard_subscribers = counts

    def _wait_until_sent_messages_are_received(self):
        """
        Wait until every subscriber has acknowledged what the added nodes' publishers sent.

        The step request and a message published just before it travel apart: the world could
        take its first steps before the message had come, and a command would act late.
        Reliable publishers hear when their messages arrive; best-effort ones never wait.
        """
        for node, _ in self._added:
            for publisher in node.publishers:
                assert publisher.wait_for_all_acked(Duration(seconds=CALL_TIMEOUT)), \
                    f'what {node.get_name()} sent on {publisher.topic_name} did not arrive ' \
                    f'within {CALL_TIMEOUT:g} s'

    def _unmatched_publishers(self):
        """
        Return the publishers of the world and the test's nodes not yet matched to a subscriber.

        A subscription made a moment ago is seen by the graph before a publisher sends it
        anything; the steps wait for that, so that their first messages reach it.
        """
        nodes = [self.world_node] + [node for node, _ in self._added]
        return [publisher for node in nodes for publisher in node.publishers
                if publisher.get_subscription_count() < node.count_subscribers(
                    publisher.topic_name) and publisher.get_subscription_count() <
                self._compatible_subscribers(node, publisher)]

    @staticmethod
    def _compatible_subscribers(node, publisher):
        """Count the subscribers of a publisher's topic that can hear it (their QoS allows)."""
        return sum(qos_check_compatible(publisher.qos_profile, info.qos_profile)[0] !=
                   QoSCompatibility.ERROR
                   for info in node.get_subscriptions_info_by_topic(publisher.topic_name))

    def _clock_callback(self, msg):
        with self._clock_changed:
            self._time_ns = msg.clock.sec * NANOSECONDS + msg.clock.nanosec
            self._clock_changed.notify_all()

    def _wait_for_clock(self, reached, timeout):
        """Wait until reached(time in ns) holds for what /clock says, or fail the test."""
        with self._clock_changed:
            assert self._clock_changed.wait_for(
                lambda: self._time_ns is not None and reached(self._time_ns), timeout), \
                f'/clock did not come as expected within {timeout} s (it says {self._time_ns} ns)'

    @staticmethod
    def wait_for(predicate, *, timeout=CALL_TIMEOUT, period=0.001):
        """Wait until predicate() is true; return whether it became true within timeout s."""
        deadline = time.monotonic() + timeout
        while not predicate():
            if time.monotonic() >= deadline:
                return bool(predicate())
            time.sleep(period)
        return True

    # --- services -----------------------------------------------------------------------------

    def call(self, srv_type, name, request, *, timeout=CALL_TIMEOUT):
        """Call a service (a name relative to the world's namespace, or a full one); answer."""
        if not name.startswith('/'):
            name = self.namespace.rstrip('/') + '/' + name
        client = self._clients.get((srv_type, name))
        if client is None:
            client = self.node.create_client(srv_type, name)
            assert client.wait_for_service(timeout_sec=timeout), \
                f'service {name} did not appear within {timeout} s'
            self._clients[(srv_type, name)] = client
        answered = threading.Event()
        future = client.call_async(request)
        future.add_done_callback(lambda _: answered.set())
        assert answered.wait(timeout), f'service {name} did not answer within {timeout} s'
        return future.result()

    def _ok(self, service, result):
        if result.result != Result.RESULT_OK:
            raise SimulationCallError(service, result)

    def spawn_entity(self, name, resource, pose=None, *, frame='', entity_namespace='',
                     allow_renaming=False):
        """
        Spawn an entity from a URDF document or a uri (package://, file://); return its name.

        pose is a Pose, (x, y, z) or (x, y, z, yaw), in the world or in frame (an entity).
        """
        request = SpawnEntity.Request(name=name, allow_renaming=allow_renaming,
                                      entity_namespace=entity_namespace)
        if resource.lstrip().startswith('<'):
            request.resource_string = resource
        else:
            request.uri = resource
        request.initial_pose.header.frame_id = frame
        request.initial_pose.pose = pose_of(pose)
        response = self.call(SpawnEntity, 'spawn_entity', request)
        self._ok('spawn_entity', response.result)
        return response.entity_name

    def delete_entity(self, name):
        """Remove an entity from the world."""
        self._ok('delete_entity', self.call(
            DeleteEntity, 'delete_entity', DeleteEntity.Request(entity=name)).result)

    def get_entities(self, pattern='', filters=None):
        """Return the names of the entities whose names match pattern (POSIX extended)."""
        filters = EntityFilters(filter=pattern) if filters is None else filters
        response = self.call(GetEntities, 'get_entities', GetEntities.Request(filters=filters))
        self._ok('get_entities', response.result)
        return list(response.entities)

    def entity_state(self, name):
        """Return an entity's ground truth: an EntityState with its pose and twist in the world."""
        response = self.call(GetEntityState, 'get_entity_state',
                             GetEntityState.Request(entity=name))
        self._ok('get_entity_state', response.result)
        return response.state

    def set_entity_state(self, name, pose, twist=None, *, frame=''):
        """Put an entity at a pose (Pose, (x, y, z) or (x, y, z, yaw)) with a twist (Twist)."""
        state = EntityState(pose=pose_of(pose))
        state.header.frame_id = frame
        if twist is not None:
            state.twist = twist
        self._ok('set_entity_state', self.call(
            SetEntityState, 'set_entity_state',
            SetEntityState.Request(entity=name, state=state)).result)

    def simulation_state(self):
        """Return the simulation's state, a SimulationState constant (STATE_PAUSED, ...)."""
        response = self.call(GetSimulationState, 'get_simulation_state',
                             GetSimulationState.Request())
        self._ok('get_simulation_state', response.result)
        return response.state.state

    def set_simulation_state(self, state):
        """Play, pause, stop or quit the simulation (a SimulationState constant)."""
        request = SetSimulationState.Request()
        request.state.state = state
        self._ok('set_simulation_state', self.call(
            SetSimulationState, 'set_simulation_state', request).result)
        if state == SimulationState.STATE_STOPPED:  # a stop resets time too
            self._wait_for_clock(lambda now: now == 0, CALL_TIMEOUT)

    def reset(self, scope=ResetSimulation.Request.SCOPE_DEFAULT):
        """Reset what scope says (ResetSimulation's SCOPE_ bits; the default: all of it)."""
        self._ok('reset_simulation', self.call(
            ResetSimulation, 'reset_simulation', ResetSimulation.Request(scope=scope)).result)
        if scope in (ResetSimulation.Request.SCOPE_DEFAULT, ResetSimulation.Request.SCOPE_ALL) \
                or scope & ResetSimulation.Request.SCOPE_TIME:
            self._wait_for_clock(lambda now: now == 0, CALL_TIMEOUT)

    # --- the end ------------------------------------------------------------------------------

    def close(self):
        """Stop every executor, destroy every node, shut the Context down, free the domain."""
        for node, executor, thread in reversed(self._spinning):
            executor.stop()
            thread.join(timeout=5.0)
            executor.shutdown(timeout_sec=5.0)
            node.destroy_node()
        self._spinning.clear()
        self._added.clear()
        self._clients.clear()
        rclpy.try_shutdown(context=self.context)
        self._claim.release()
