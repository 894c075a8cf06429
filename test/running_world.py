"""The world node started on the test harness: its /clock as received, its ticks, its services."""

import time

from geometry_msgs.msg import Pose, Twist
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock
from service_tutorial.conversions import seconds_of
from service_tutorial.lesson.r2d2 import spawn_pose
from service_tutorial.lesson_world import lesson_world
from srv_interfaces.srv import DeleteModel, GetModelList, GetModelState, SetModelState
from srv_interfaces.srv import SpawnModel
from std_srvs.srv import Empty


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
        self.clock = []  # (wall time received, simulation time) of each /clock message
        ros.client_node.create_subscription(
            Clock, '/clock', lambda msg: self.clock.append((time.monotonic(),
                                                            seconds_of(msg.clock))), 100)
        assert ros.wait_for(lambda: self.clock, timeout=10.0), 'no /clock from the world'

    def now(self):
        """Return the simulation time the world last published on /clock."""
        return self.clock[-1][1]

    def wait_sim(self, duration, *, timeout=None):
        """Wait until /clock has gone on by duration seconds of simulation time."""
        end = self.now() + duration
        timeout = 60.0 + 10.0 * duration if timeout is None else timeout
        assert self.ros.wait_for(lambda: self.now() >= end, timeout=timeout), \
            f'simulation time did not reach {end:.3f} s within {timeout} s'

    def wait_ticks(self, count):
        """Wait until the world's step timer has fired count more times."""
        end = self.ticks + count
        assert self.ros.wait_for(lambda: self.ticks >= end, timeout=10.0 + 0.1 * count)

    def call(self, srv_type, service, request, *, timeout=10.0):
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

    def spawn(self, name, xml, pose=None, frame='', namespace='', *, timeout=10.0):
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
        assert self.ros.wait_for(
            lambda: all(model.topics_made for model in list(self.node.models.values())),
            timeout=10.0), 'the world did not make the topics of its models'
        publishers = list(self.node.publishers) + self.node.sensor_node.publishers
        return {publisher.topic_name for publisher in publishers}

    def topics(self):
        """Return the topics the world node publishes or subscribes to, as published_topics."""
        return self.published_topics() | {
            subscription.topic_name for subscription in self.node.subscriptions}

    def drive(self, commands, duration):
        """Publish {topic: Twist} for duration s of simulation time, then stop and settle."""
        node = self.ros.client_node
        publishers = {topic: node.create_publisher(Twist, topic, 10) for topic in commands}
        assert self.ros.wait_for(lambda: all(publisher.get_subscription_count() > 0
                                             for publisher in publishers.values())), \
            f'nobody subscribes to {list(commands)}'
        end = self.now() + duration
        while self.now() < end:
            for topic, twist in commands.items():
                publishers[topic].publish(twist)
            self.wait_sim(0.01)
        for publisher in publishers.values():
            publisher.publish(Twist())
        self.wait_sim(0.5)
        for publisher in publishers.values():
            self.ros.destroy(publisher)
