"""
The world node started on the test harness: its /clock as received, its ticks, its services.

A test of the world's behaviour starts it paused and moves time with step(n), as the testing
fixture's SimulatedWorld does: exactly n steps through StepSimulation, and what they sent is
in the client's lists when step() returns. A velocity command goes in with command(): published,
and taken by the world before the next steps, so that it acts from a known step. wait_sim()
is for the few tests of a playing world, where time runs on its own.
"""

import time

from geometry_msgs.msg import Pose, Twist
from rclpy.parameter import Parameter
from rclpy.qos import qos_check_compatible, QoSCompatibility
from rosgraph_msgs.msg import Clock
from service_tutorial.conversions import seconds_of
from service_tutorial.lesson.r2d2 import spawn_pose
from service_tutorial.lesson_world import lesson_world
from service_tutorial.testing.simulated_world import CALL_TIMEOUT
from service_tutorial.world_node.subscribers import SUBSCRIBER_CHECK_PERIOD
from simulation_interfaces.msg import Result
from simulation_interfaces.srv import StepSimulation
from srv_interfaces.srv import DeleteModel, GetModelList, GetModelState, SetModelState
from srv_interfaces.srv import SpawnModel
from std_srvs.srv import Empty

# Simulated time between two commands of a drive (drive()), in steps: 0.1 s at 0.002 s a step,
# well within the default cmd_vel_timeout of 0.5 s.
COMMAND_STEPS = 50


def lesson_pose():
    """Return R2-D2's pose in the lesson: (-2, 1, 1), turned -90 degrees about z."""
    return spawn_pose()


class RunningWorld:
    """The world as mujoco_world runs it, spinning on the harness: its /clock and services."""

    def __init__(self, ros, **parameters):
        self.ros = ros
        self.node = lesson_world(parameter_overrides=[
            Parameter(name, value=value) for name, value in parameters.items()])
        # Count the ticks of the step timer: each one is a chance for the world to step.
        self.ticks = 0
        step = self.node.step_timer.callback

        def counted_step():
            step()
            self.ticks += 1
        self.node.step_timer.callback = counted_step
        ros.add_node(self.node)
        self._clients = {}
        self._heard_subscribers = {}  # topic of the world -> its subscribers at the last step
        self._commands = {}  # topic -> the publisher of command()
        self._taken = {}  # drive face -> how many commands the world took from its cmd_vel
        self.clock = []  # (wall time received, simulation time) of each /clock message
        ros.client_node.create_subscription(
            Clock, '/clock', lambda msg: self.clock.append((time.monotonic(),
                                                            seconds_of(msg.clock))), 100)
        assert ros.wait_for(lambda: self.clock), 'no /clock from the world'

    def now(self):
        """Return the simulation time the world last published on /clock."""
        return self.clock[-1][1]

    @property
    def timestep(self):
        """Return the world's physics step, in s."""
        return self.node.world.timestep

    def steps(self, duration):
        """Return a duration of simulated time (s) in whole steps of the world."""
        return round(duration / self.timestep)

    def step(self, steps=1, *, timeout=None):
        """
        Take exactly steps steps of the paused world through StepSimulation; return the time.

        Returns once the world has answered, /clock says so and the harness's nodes have
        handled what the steps sent them (RosHarness.settle), as SimulatedWorld.step() does.
        """
        timeout = 10.0 + 1e-3 * steps if timeout is None else timeout
        self._wait_until_new_subscribers_are_heard()
        end = self.node.world.time + steps * self.timestep
        result = self.call(StepSimulation, '/step_simulation',
                           StepSimulation.Request(steps=steps), timeout=timeout).result
        assert result.result == Result.RESULT_OK, result.error_message
        assert self.ros.wait_for(lambda: self.now() >= end - self.timestep / 2, timeout=timeout), \
            f'/clock says {self.now()} s after the steps, not {end} s'
        self.ros.settle(timeout)
        return self.now()

    def _world_publishers(self):
        return list(self.node.publishers) + self.node.sensor_node.publishers

    def _wait_until_new_subscribers_are_heard(self):
        """
        Wait until the world's next messages reach every subscriber that came since the last steps.

        As SimulatedWorld's: the publishers of the world and the test have matched every
        subscriber the graph shows, and the world, which asks whether anyone listens once per
        SUBSCRIBER_CHECK_PERIOD of wall time, has asked since a new one came.
        """
        publishers = self._world_publishers() + list(self.ros.client_node.publishers)

        def unmatched():
            return [publisher.topic_name for publisher in publishers
                    if publisher.get_subscription_count() < self._hearing(publisher)]
        assert self.ros.wait_for(lambda: not unmatched()), \
            f'publishers that still miss subscribers: {unmatched()}'
        counts = {publisher.topic_name: publisher.get_subscription_count()
                  for publisher in self._world_publishers()}
        if any(count > self._heard_subscribers.get(topic, 0) for topic, count in counts.items()):
            time.sleep(SUBSCRIBER_CHECK_PERIOD)
        self._heard_subscribers = counts

    def _hearing(self, publisher):
        """Count the subscribers of a publisher's topic that can hear it (their QoS allows)."""
        return sum(qos_check_compatible(publisher.qos_profile, info.qos_profile)[0] !=
                   QoSCompatibility.ERROR
                   for info in self.node.get_subscriptions_info_by_topic(publisher.topic_name))

    def command(self, topic, twist):
        """Publish a velocity command on a drive's topic; return once the world has taken it."""
        face = self._drive_face(topic)
        publisher = self._commands.get(topic)
        if publisher is None:
            publisher = self.ros.client_node.create_publisher(Twist, topic, 10)
            # Both ends matched: a message the world's reader does not know the writer of is lost.
            assert self.ros.wait_for(lambda: publisher.get_subscription_count() > 0
                                     and face.cmd_vel_sub.get_publisher_count() > 0), \
                f'the world does not hear {topic}'
            self._commands[topic] = publisher
        taken = self._taken[face]
        publisher.publish(twist)
        # A paused world takes the commands that came at each of its ticks (taken_at_tick.py).
        assert self.ros.wait_for(lambda: self._taken[face] > taken), \
            f'the world did not take the command on {topic}'

    def _drive_face(self, topic):
        """Return the drive face whose cmd_vel is topic, counting the commands it takes."""
        assert self.ros.wait_for(lambda: all(
            model.topics_made for model in list(self.node.models.values())))
        faces = [face for model in list(self.node.models.values()) for face in model.faces
                 if getattr(face, 'cmd_vel_sub', None) is not None
                 and face.cmd_vel_sub.topic_name == topic]
        assert faces, f'no drive of the world takes commands on {topic}'
        face = faces[0]
        if face not in self._taken:
            self._taken[face] = 0
            take = face.cmd_vel_callback

            def counted(msg):
                take(msg)
                self._taken[face] += 1
            face.cmd_vel_callback = counted
        return face

    def drive(self, commands, duration, *, rest=0.5):
        """
        Command {topic: Twist} for duration s of simulated time, then stop and rest rest s.

        Each command is taken again every COMMAND_STEPS steps, as a teleop node sends it again,
        and the steps are whole: duration and rest are rounded to the world's steps.
        """
        steps = self.steps(duration)
        for start in range(0, steps, COMMAND_STEPS):
            for topic, twist in commands.items():
                self.command(topic, twist)
            self.step(min(COMMAND_STEPS, steps - start))
        for topic in commands:
            self.command(topic, Twist())
        if rest > 0:
            self.step(self.steps(rest))

    def wait_sim(self, duration, *, timeout=None):
        """Wait until /clock of a playing world has gone on by duration s of simulation time."""
        end = self.now() + duration
        timeout = 60.0 + 10.0 * duration if timeout is None else timeout
        assert self.ros.wait_for(lambda: self.now() >= end, timeout=timeout), \
            f'simulation time did not reach {end:.3f} s within {timeout} s'

    def wait_ticks(self, count):
        """Wait until the world's step timer has fired count more times."""
        end = self.ticks + count
        assert self.ros.wait_for(lambda: self.ticks >= end, timeout=CALL_TIMEOUT + 0.1 * count)

    def call(self, srv_type, service, request, *, timeout=CALL_TIMEOUT):
        """
        Call a service of the world through a client kept for later.

        service is a lesson service's name under /mujoco/, or a full name ('/spawn_entity').
        """
        name = service if service.startswith('/') else '/mujoco/' + service
        client = self._clients.get(name)
        if client is None:
            client = self.ros.client_node.create_client(srv_type, name)
            assert client.wait_for_service(timeout_sec=10.0), f'no {name}'
            self._clients[name] = client
        future = client.call_async(request)
        assert self.ros.wait_for(future.done, timeout=timeout), \
            f'{name} did not answer within {timeout} s'
        return future.result()

    def spawn(self, name, xml, pose=None, frame='', namespace='', *, timeout=CALL_TIMEOUT):
        """Ask for a model to be spawned; return the answer."""
        return self.call(SpawnModel, 'spawn_urdf_model', SpawnModel.Request(
            model_name=name, model_xml=xml, robot_namespace=namespace,
            initial_pose=pose or Pose(), reference_frame=frame), timeout=timeout)

    def spawn_or_fail(self, name, xml, pose=None, namespace=''):
        """Spawn a model the test needs; fail the test with the world's answer if refused."""
        response = self.spawn(name, xml, pose, namespace=namespace)
        assert response.success, response.status_message
        return response

    def delete(self, name):
        """Ask for a model to be deleted; return the answer."""
        return self.call(DeleteModel, 'delete_model', DeleteModel.Request(model_name=name))

    def state(self, name, frame=''):
        """Return a model's state, in the world or in a reference frame."""
        return self.call(GetModelState, 'get_model_state',
                         GetModelState.Request(model_name=name, reference_frame=frame))

    def set_state(self, name, pose, twist=None):
        """Ask for a model to be moved; return the answer."""
        return self.call(SetModelState, 'set_model_state', SetModelState.Request(
            model_name=name, pose=pose, twist=twist or Twist()))

    def models(self):
        """Return the names of the models in the world, in spawn order."""
        return list(self.call(GetModelList, 'get_model_list',
                              GetModelList.Request()).model_names)

    def empty(self, service):
        """Call one of the world's std_srvs/Empty services: pause_physics, reset_world..."""
        return self.call(Empty, service, Empty.Request())

    def published_topics(self):
        """Return the topics the world publishes (its sensor node too), once all are made."""
        # The world makes a model's topics right after it answers the spawn.
        assert self.ros.wait_for(lambda: all(
            model.topics_made for model in list(self.node.models.values()))), \
            'the world did not make the topics of its models'
        publishers = list(self.node.publishers) + self.node.sensor_node.publishers
        return {publisher.topic_name for publisher in publishers}

    def topics(self):
        """Return the topics the world node publishes or subscribes to, as published_topics."""
        return self.published_topics() | {
            subscription.topic_name for subscription in self.node.subscriptions}
