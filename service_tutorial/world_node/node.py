"""
The MuJoCo world node: the Gazebo of this tutorial.

It steps a service_tutorial.sim.world.World, serves the world services under /mujoco/
(gazebo_services.py) and the standard simulation interfaces beside them (standard/), and
publishes /clock; each model's own topics (cmd_vel, odom and joint_states of a diff drive, its
odometry on /tf) come from the faces of its ModelInterface, named when the model is spawned
and made as soon as the spawn is answered, and a model with topics also gets its URDF on
robot_description. A Pacer decides how far each tick steps and which streams are due. Stepping
runs in a timer of the node's default callback group, so a service callback, a parameter change
and a physics step never run at the same time and no locks are needed. Each tick first takes
the velocity commands that came since the last one: they never wake the executor
(taken_at_tick.py). A paused world steps only when a client asks for N steps
(requested_steps.py): the timer takes them, a share of every tick, while the client's call
waits in a callback group of its own. A model the world removes by itself, because it kept
breaking the physics (sim/recovery.py), is announced on ~/removed_models.

The parameters are declared in parameters.py, and every one that is not read-only takes
effect as soon as it is set. What the simulation logs reaches the node's logger (and /rosout).
"""

import time

from rclpy.clock import Clock as WallClock, ClockType
from rclpy.event_handler import PublisherEventCallbacks
from rclpy.logging import LoggingSeverity
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from rosgraph_msgs.msg import Clock
from service_tutorial.conversions import fill_time_msg
from service_tutorial.node_main import spin_node
from service_tutorial.sim.recovery import Removal
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.bridge_channel import BridgeChannel
from service_tutorial.world_node.camera_stream import CAMERA_PARAMETERS, CameraStream
from service_tutorial.world_node.collections_between_ticks import CollectionsBetweenTicks
from service_tutorial.world_node.gazebo_services import GazeboServices
from service_tutorial.world_node.gz_bridge import GzBridge
from service_tutorial.world_node.log_forwarding import forward_core_logs, log_here
from service_tutorial.world_node.model_interface import ModelInterface, Roster
from service_tutorial.world_node.pacing import CLOCK_STREAM, JOINT_STATES_STREAM
from service_tutorial.world_node.pacing import heard_by_pacer, ODOMETRY_STREAM, Pacer
from service_tutorial.world_node.packages import package_share
from service_tutorial.world_node.parameters import declare_world_parameters, default_parameters
from service_tutorial.world_node.parameters import run_or_exit
from service_tutorial.world_node.requested_steps import RequestedSteps
from service_tutorial.world_node.ros_names import normalise_namespace
from service_tutorial.world_node.sensor_node import SensorNode
from service_tutorial.world_node.standard.features import FeatureService
from service_tutorial.world_node.standard.simulation import SimulationServices
from service_tutorial.world_node.standard.stepping import SteppingServices
from service_tutorial.world_node.tf_publishing import TransformBatch
from service_tutorial.world_node.viewer import PassiveViewer
from srv_interfaces.msg import RemovedModel

PACKAGE = 'service_tutorial'
# Wall time between two looks of the sensor faces for subscribers and for holds that end, in s.
FACE_LOOK_PERIOD = 0.01
# As gazebo_ros publishes /clock: the latest time waits for every subscriber, a late one too.
CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
# A tool that starts watching late still hears of the last few models the world removed.
REMOVED_MODELS_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE,
                                durability=DurabilityPolicy.TRANSIENT_LOCAL)
# The parameter that gives each publication stream its rate, in Hz.
RATE_PARAMETERS = {CLOCK_STREAM: 'clock_publish_rate', ODOMETRY_STREAM: 'odom_publish_rate',
                   JOINT_STATES_STREAM: 'joint_state_publish_rate'}


def left_out_of(description):
    """Say which meshes and plugins of a spawned robot the world left out, or return ''."""
    parts = []
    meshes = description.missing_meshes
    if meshes:
        parts.append(f'{len(meshes)} {"mesh" if len(meshes) == 1 else "meshes"} not found, '
                     f'left out: {", ".join(meshes)}')
    if description.ignored_plugins:
        parts.append(f'plugins not simulated: {", ".join(description.ignored_plugins)}')
    return '; '.join(parts)


def robot_description(order):
    """Return the URDF a spawned model's robot_description carries; MJCF carries none."""
    return order.text if order.model_format == 'urdf' else None


class MujocoWorld(Node):
    """Serves a MuJoCo world the way gazebo_ros serves Gazebo's."""

    def __init__(self, *, web_panel=None, **kwargs):
        """
        Start the world.

        web_panel: the panel its web page shows (web:=true), a subclass of web.panel.Panel
        that adds its controls (lesson_world.py hands it the lesson's); None: the page's own.
        """
        super().__init__('mujoco', **kwargs)
        self.parameters = parameters = declare_world_parameters(self)  # ParameterError if bad
        if parameters['web']:
            # Before the world is made: without viser the world ends here, as on a bad value.
            from service_tutorial.world_node.web.page import import_viser
            import_viser()
        self.forwarded_logs = forward_core_logs(self)
        self._web_panel = web_panel
        try:
            self._start(parameters)
        except BaseException:
            self.forwarded_logs.stop()
            raise
        # The world is built: full collections never walk it again, nor fall into a call.
        self.collections = CollectionsBetweenTicks()
        log_here(self.get_logger(), LoggingSeverity.INFO,
                 f'MuJoCo world ready: {", ".join(self.world.model_names()) or "no models"}, '
                 f'timestep {self.world.timestep} s, real_time_factor '
                 f'{parameters["real_time_factor"]}')

    def serve(self, srv_type, srv_name, callback, **kwargs):
        """Create a service of the world, whose answers the pacer hears of (Pacer.answered)."""
        return self.create_service(srv_type, srv_name, heard_by_pacer(self.pacer, callback),
                                   **kwargs)

    def _start(self, parameters):
        """Make the world, its services and topics, and the start-up models."""
        # Imported here, after the parameters passed their checks: a bad one ends the program
        # before the simulation's imports (yourdfpy and trimesh take over a second).
        from service_tutorial.sim.scene import EARTH_GRAVITY
        from service_tutorial.sim.world import World
        from service_tutorial.world_node.standard.entities import EntityServices
        from service_tutorial.world_node.standard.named_poses import NamedPoseServices
        from service_tutorial.world_node.standard.spawnables import SpawnableServices
        from service_tutorial.world_node.standard.worlds import WorldServices
        from service_tutorial.world_node.world_loader import WorldLoader
        self.world_loader = WorldLoader(self, package_share)
        start_up = self.world_loader.start_up_world(parameters, default_parameters())
        self.world = World(timestep=start_up.timestep if start_up else parameters['timestep'],
                           gravity=start_up.gravity if start_up else EARTH_GRAVITY,
                           cmd_vel_timeout=parameters['cmd_vel_timeout'],
                           package_resolver=package_share,
                           scenery=start_up and start_up.scenery,
                           background_rendering=True,  # a camera never holds up an answer
                           **(start_up.place if start_up else {}))
        self.pacer = Pacer(timestep=self.world.timestep,
                           real_time_factor=parameters['real_time_factor'],
                           periods={stream: 1.0 / parameters[name]
                                    for stream, name in RATE_PARAMETERS.items()})
        self._clock_msg = Clock()
        self.models = {}  # name -> ModelInterface, in spawn order
        self._roster = Roster(())  # their faces; None: to gather again (roster())
        # How the gz-sim systems' and sensors' gz topics are served on ROS (set_gz_bridge).
        self.gz_bridge = GzBridge()
        self._next_gz_bridge = None
        self._gz_bridge_due = self.create_guard_condition(self.apply_gz_bridge)
        self._topics_to_make = []  # interfaces of models spawned, topics made once answered
        # Made after the service callback that spawned returns, before the next step.
        self._topics_due = self.create_guard_condition(self.make_model_topics)
        self._next_face_look = 0.0  # wall time
        self.requested_steps = RequestedSteps(self)  # StepSimulation, SimulateSteps
        self.quitting = Future()  # done when a client asks the world to quit: main() ends

        # Reliable and transient local, /clock suits every subscriber's QoS: rclpy's default
        # handlers of incompatible QoS would only add to every executor turn's wait set.
        self.clock_pub = self.create_publisher(
            Clock, '/clock', CLOCK_QOS,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        self.tf_batch = TransformBatch(self)  # /tf, for every drive's OdomTfFace
        # Publishes the sensors' topics, from a participant of its own if it may (sensor_node.py).
        self.sensor_node = SensorNode(self)
        # The parameter_bridge processes running change the mappings (bridge_channel.py); each
        # change re-makes the gz faces' topics at the node's next turn.
        self.gz_bridge.on_change(lambda: self.set_gz_bridge(self.gz_bridge))
        self.bridge_channel = BridgeChannel(self)
        # Each model the world removes by itself to save the others, with the reason. Like
        # /clock, it suits every subscriber's QoS: no default event handlers in every turn.
        self.removed_models_pub = self.create_publisher(
            RemovedModel, '~/removed_models', REMOVED_MODELS_QOS,
            event_callbacks=PublisherEventCallbacks(use_default_callbacks=False))
        # The lesson's world services under ~/ (/mujoco/ by default), as gazebo_ros serves them.
        self.gazebo_services = GazeboServices(self)
        # The ROS 2 standard simulation interfaces, relative to the node's namespace.
        simulation = SimulationServices(self)
        self.stepping_services = SteppingServices(self, simulation)
        self.standard_groups = [
            simulation, self.stepping_services, EntityServices(self),
            WorldServices(self, simulation, package_share),
            NamedPoseServices(self), SpawnableServices(self)]
        self.feature_service = FeatureService(self, self.standard_groups)
        # ~/camera/image_raw, ~/camera/camera_info (camera_enabled) and ~/save_snapshot.
        self.camera_stream = CameraStream(self, self.world, parameters)

        self.viewer = PassiveViewer(self.world, self.get_logger(), enabled=parameters['gui'])
        self.world_loader.begin(start_up)
        if parameters['paused']:
            self.world.pause()
        self.web_page = None
        if parameters['web']:
            from service_tutorial.world_node.web.page import WebPage
            self.web_page = WebPage(self, parameters['web_host'], parameters['web_port'],
                                    self._web_panel)
            self.get_logger().info(f'web page: {self.web_page.address}')

        # Every parameter that is not read-only takes effect when it is set.
        parameters.on_change(self.pace_changed, ['real_time_factor', *RATE_PARAMETERS.values()])
        parameters.on_change(self.paused_changed, ['paused'])
        parameters.on_change(self.cmd_vel_timeout_changed, ['cmd_vel_timeout'])
        parameters.on_change(self.camera_stream.configure, CAMERA_PARAMETERS)

        # Free-running stepping uses a zero-period timer: it fires on every executor turn,
        # and the executor serves pending service calls between two turns.
        # The world is the source of /clock, so it paces itself on the steady wall clock even
        # when use_sim_time is set (a sim-time timer would wait for its own /clock forever).
        self.step_timer = self.create_timer(
            self.pacer.first_tick_period, self.step_callback,
            clock=WallClock(clock_type=ClockType.STEADY_TIME))
        self.publish_clock()

    # --- parameters set at run time -----------------------------------------------------------

    def pace_changed(self, changes):
        """Apply a new real_time_factor (0: free-running) or publish rate from now on."""
        for stream, name in RATE_PARAMETERS.items():
            if name in changes:
                self.pacer.set_period(stream, 1.0 / changes[name])
        if 'real_time_factor' in changes:
            self.pacer.set_real_time_factor(changes['real_time_factor'], self.world.time)
            self.step_timer.timer_period_ns = self.pacer.tick_period_ns(self.world.paused)

    def paused_changed(self, changes):
        """Stop or resume stepping, whether the parameter or a pause service asked."""
        if changes['paused']:
            self.world.pause()
            # Free-running, /clock lags the steps by up to a period: the latched message a
            # late subscriber gets must be the time the world stopped at.
            self.publish_clock()
        else:
            self.requested_steps.stop('set playing')
            self.world.unpause()
            self.pacer.anchor(self.world.time)

    def cmd_vel_timeout_changed(self, changes):
        """Let every drive command lapse after the new timeout, those in force too."""
        self.world.set_cmd_vel_timeout(changes['cmd_vel_timeout'])

    # --- stepping -----------------------------------------------------------------------------

    def step_callback(self):
        """Advance the physics as the pacer says, publishing what falls due on the way."""
        world, pacer = self.world, self.pacer
        if pacer.resting():  # calls waiting are answered first
            return
        pacer.start_tick()
        self.apply_gz_bridge()
        self.make_model_topics()
        for take_commands in self.roster().take_commands:
            take_commands()  # they never wake the executor: see taken_at_tick.py
        stepping = self.requested_steps
        period_ns = 0 if stepping.busy else pacer.tick_period_ns(world.paused)
        if self.step_timer.timer_period_ns != period_ns:
            self.step_timer.timer_period_ns = period_ns
        if world.paused:
            if stepping.busy:
                stepping.tick()
            pacer.anchor(world.time)
            if pacer.repeat_due():  # the same time again, for a late joiner
                self.publish_clock()
        else:
            for steps in pacer.chunks(lambda: world.time, lambda: self.camera_stream.next_due):
                world.step(steps)
                self.publish_due()
        self.publish_due()
        self.viewer.sync()
        if self.web_page is not None:
            self.web_page.tick()  # returns at once while no browser is connected
        # Steps on request (paused) keep every turn: with another Python thread in the process
        # (a test's, the benchmark's client), a turn given up after each tick cost StepSimulation
        # a quarter of its speed.
        self.world.release_replaced()
        self.collections.collect_if_due()
        pacer.end_tick(back_to_back=period_ns == 0 and not world.paused)

    def publish_due(self):
        """Publish /clock, the models' streams and the camera where their time has come."""
        for removal in self.world.take_removed_models():  # they kept blowing up
            self.forget_model(removal.name)
            self._announce_removal(removal)
        self.world.background_renders.deliver()  # the cameras' frames drawn meanwhile
        now, roster = self.world.time, self.roster()
        for stream, stamp in self.pacer.take_due(now):
            if stream == CLOCK_STREAM:
                self._publish_clock_msg(stamp)
            else:
                for publish in roster.publishing.get(stream, ()):
                    publish(stream, stamp)
                self.tf_batch.send()
        wall = time.monotonic()
        if wall >= self._next_face_look:
            self._next_face_look = wall + FACE_LOOK_PERIOD
            for watcher in roster.watchers:
                if wall >= watcher.next_look:
                    watcher.look(wall)
        self.camera_stream.publish_due(now)

    def _announce_removal(self, removal):
        """Tell ~/removed_models which model the world removed by itself, when and why."""
        msg = RemovedModel(model_name=removal.name, reason=removal.reason)
        fill_time_msg(msg.stamp, removal.time)
        self.removed_models_pub.publish(msg)

    def publish_clock(self):
        """Publish the simulation time on /clock."""
        now = self.world.time
        self.pacer.published(CLOCK_STREAM, now)
        self._publish_clock_msg(now)

    def _publish_clock_msg(self, now):
        fill_time_msg(self._clock_msg.clock, now)
        self.clock_pub.publish(self._clock_msg)

    # --- model services -----------------------------------------------------------------------

    def spawn_models(self, orders, namespaces):
        """
        Add the models of SpawnOrders with one recompile, each with its ROS interface.

        namespaces: each model's robot namespace, as asked. Return, for each order, what the
        world left out of its model ('' for nothing) or the exception that refused it (a
        WorldError with its reason, unless a bug).
        """
        self.world_loader.check_loaded('spawning')
        outcomes, ready = [None] * len(orders), []
        for index, namespace in enumerate(namespaces):
            try:  # refused before the world is asked: a bad namespace leaves it untouched
                ready.append((index, normalise_namespace(namespace)))
            except WorldError as error:
                outcomes[index] = error
        spawned = self.world.spawn([orders[index] for index, _ in ready])
        for (index, namespace), model in zip(ready, spawned):
            outcomes[index] = model
            if not isinstance(model, WorldError):
                try:
                    self._give_interface(model, namespace, robot_description(orders[index]))
                    # The world's log has already named each of them, with the reason.
                    outcomes[index] = left_out_of(model.description)
                except Exception as error:  # the model is gone again; the others go on
                    outcomes[index] = error
        self.viewer.reopen()
        return outcomes

    def _give_interface(self, model, namespace, urdf):
        """Name a model's topics, to be made once answered; if one cannot be, delete it again."""
        try:
            interface = self.models[model.name] = ModelInterface(
                self, self.world, model, namespace, urdf)
        except Exception:
            self.world.delete_model(model.name)
            raise
        self._topics_to_make.append(interface)
        self._topics_due.trigger()

    def make_model_topics(self):
        """Make the topics of the models spawned since the last call, if still in the world."""
        waiting, self._topics_to_make = self._topics_to_make, []
        if waiting:
            self._roster = None  # the new faces join it, or the refused ones leave it
        for interface in waiting:
            name = interface.model_name
            if self.models.get(name) is not interface:
                continue  # deleted, or deleted and spawned again, before its topics were made
            try:
                interface.make_topics()
            except Exception as error:  # the middleware's: every name was checked at spawn
                reason = f'its topics could not be made ({error})'
                self.get_logger().error(f'model {quoted(name)}: {reason}; removed it from the '
                                        'world')
                self.models.pop(name)
                self.world.delete_model(name)
                self._announce_removal(Removal(name, self.world.time, reason))
        if waiting:  # part of answering the spawns: the callers' next calls come after
            self.pacer.answered()

    def delete_model(self, name):
        """Remove a model from the world along with its ROS interface."""
        self.world.delete_model(name)
        self.forget_model(name)
        self.viewer.reopen()

    def set_gz_bridge(self, bridge):
        """
        Serve the gz topics as a GzBridge says, from the node's next turn on, from any thread.

        Then every gz face destroys its topics and makes them again under the bridge's names
        and types (apply_gz_bridge); the robots run on, and keep their state.
        """
        self._next_gz_bridge = bridge
        self._gz_bridge_due.trigger()

    def apply_gz_bridge(self):
        """Serve every robot's gz topics as the bridge last set says, if it changed."""
        bridge, self._next_gz_bridge = self._next_gz_bridge, None
        if bridge is None:
            return
        self._roster = None
        if bridge is not self.gz_bridge:
            bridge.on_change(lambda: self.set_gz_bridge(bridge))
        self.gz_bridge = bridge
        for name, interface in self.models.items():
            try:
                interface.remake_gz_topics()
            except Exception as error:  # the middleware's: the others are served still
                self.get_logger().error(f'model {quoted(name)}: its gz topics could not be '
                                        f'made again ({error}); it has no topics now')
                interface.destroy()

    def holding_time(self, operation):
        """Return operation, made to hold simulation time for as long as it runs."""
        def held():
            start = time.monotonic()
            try:
                return operation()
            finally:
                if self.pacer.hold(start):
                    self.step_timer.reset()  # the next tick a whole period from now
        return held

    def forget_model(self, name):
        """Destroy the ROS interface of a model that left the world."""
        interface = self.models.pop(name, None)
        if interface is not None:
            interface.destroy()
            self._roster = None

    def roster(self):
        """Return the Roster of the models' faces, gathered again after a change."""
        if self._roster is None:
            self._roster = Roster(self.models.values())
        return self._roster

    def after_reset(self):
        """
        Start the streams again from the world's time after a reset, and publish that time.

        The streams' messages of the reset state are due at once and go out at the next tick,
        after the answer: published inside the call, they made a reset_world cost twice a
        trivial service's round trip.
        """
        self.pacer.timestep = self.world.timestep  # a world loaded may have its own
        self.pacer.anchor(self.world.time)
        self.pacer.restart(self.world.time, (ODOMETRY_STREAM, JOINT_STATES_STREAM))
        self.publish_clock()

    def destroy_node(self):
        """Close the viewer and the action server along with the node; stop passing logs on."""
        self.viewer.close()
        if self.web_page is not None:
            self.web_page.close()
            self.web_page = None
        self.camera_stream.close()
        self.world.background_renders.close()
        self.forwarded_logs.stop()
        # An action server keeps the node's handle alive (and its /rosout) until destroyed.
        self.stepping_services.destroy()
        self.sensor_node.destroy()
        self.bridge_channel.destroy()
        self.collections.close()
        return super().destroy_node()


def main(args=None, *, web_panel=None):
    """
    Run the MuJoCo world until Ctrl-C or a client asks it to quit, then end with status 0.

    A bad parameter ends it with one line, status 2. web_panel: as MujocoWorld's.
    """
    return spin_node(lambda: run_or_exit('mujoco_world', MujocoWorld, web_panel=web_panel),
                     args=args, done=lambda world: world.quitting)


if __name__ == '__main__':
    main()
