"""
The standard simulation interfaces against MuJoCo's own limits: a batch spawn, stepping, states.

The world node runs in this process, paused, on an executor thread of its own shared with a
trivial std_srvs/Trigger service, and is called from the observer (the layout of round_trips.py).
Its figure and the one it is compared with are taken in turns, round by round, so that both see
the same load on a shared machine; the rows give medians of the rounds, but stepping gives the
best of each, as the core's stepping row does: on this shared machine the same 10,000 bare
steps took from 0.8 to 1.4 s from one round to the next.
"""

import ctypes
import time

from fleet import core_fleet, DRIVE_ANGULAR_Z, Fleet, fleet_names, fleet_parameters
from fleet import fleet_position, RawFleet, read_model
from harness import BenchmarkError, ExecutorThread, prompt_thread_switches, quiet_console
from harness import THREAD_SWITCH_INTERVAL, wait_until
import mujoco
from rcl_client import RclClient, Sequence, String
from report import median_ms, percentiles, Table
from round_trips import TrivialService
from service_tutorial.testing.spawns import spawn_robot
from spawn_cost import BareWorld

# SpawnEntities of a batch: at most this many times MuJoCo's own path for the same batch, plus
# two Trigger round trips; and at least SINGLES_FACTOR times faster than as many SpawnEntity.
BATCH_LIMIT = 1.5
SINGLES_FACTOR = 10.0
# StepSimulation: at most this many times bare mj_step of the same steps, plus two Trigger.
STEP_LIMIT = 1.2
# Each of the three limits allows the service this many Trigger round trips more.
TRIGGERS_ALLOWED = 2.0
# How a client of the standard names tinybot: the file this package installs.
TINYBOT_URI = 'package://service_tutorial/models/tinybot.urdf'
# The topics the world makes for one tinybot: cmd_vel, odom, joint_states, scan, image,
# camera_info, imu and robot_description.
TOPICS_PER_TINYBOT = 8
# Steps the driving fleet takes before the stepping rounds, and to check it drives.
STEP_WARM_UP = 500
# A call that comes while StepSimulation steps waits for the tick in progress: its p99 at most
# this (ms). A tick steps for 50 ms of wall time at most.
DURING_STEPPING_LIMIT = 200.0
# The most steps one StepSimulation takes: far more than the calls during it last (10 tinybots
# step about 8,000 times a wall second). Playing ends it (set_simulation_state).
LONG_STEPPING = 1_000_000
RESULT_OK = 1  # simulation_interfaces/msg/Result


class CResult(ctypes.Structure):
    """simulation_interfaces/msg/Result as a C struct."""

    _fields_ = [('result', ctypes.c_uint8), ('error_message', String)]


class CStatesResponse(ctypes.Structure):
    """GetEntitiesStates.Response as a C struct: the result, the names and their states."""

    _fields_ = [('result', CResult), ('entities', Sequence), ('states', Sequence)]


class CTriggerResponse(ctypes.Structure):
    """std_srvs/Trigger.Response as a C struct."""

    _fields_ = [('success', ctypes.c_bool), ('message', String)]


class StandardWorld:
    """The world node in this process, paused, beside a trivial Trigger service."""

    def __init__(self, observer, parameters):
        from rclpy.parameter import Parameter
        from service_tutorial.world_node.node import MujocoWorld
        from std_srvs.srv import Trigger
        self._observer = observer
        # An empty list's type cannot be told from its value: the only one here is 'models'.
        overrides = [Parameter(name, Parameter.Type.STRING_ARRAY, value) if value == []
                     else Parameter(name, value=value)
                     for name, value in {**parameters, 'paused': True}.items()]
        self.node = MujocoWorld(parameter_overrides=overrides)
        self._trivial = TrivialService()
        self._executor_thread = ExecutorThread(self.node, self._trivial.node)
        try:
            observer.wait_for_service(Trigger, '/benchmark_trivial/trigger')
        except BaseException:
            self.close()
            raise

    def call(self, srv_type, name, request, *, timeout=120.0):
        """Call one of the standard's services; raise BenchmarkError unless it succeeds."""
        from simulation_interfaces.msg import Result
        self._observer.wait_for_service(srv_type, name)
        response = self._observer.call(srv_type, name, request, timeout=timeout)
        if response.result.result != Result.RESULT_OK:
            raise BenchmarkError(f'{name} answered {response.result.result}: '
                                 f'{response.result.error_message}')
        return response

    def timed(self, srv_type, name, request):
        """Return the wall time of one successful call, from request to answer, in s."""
        self._observer.wait_for_service(srv_type, name)
        start = time.perf_counter()
        self.call(srv_type, name, request)
        return time.perf_counter() - start

    def trigger(self):
        """Return the wall time of one trivial Trigger round trip, in s."""
        from std_srvs.srv import Trigger
        start = time.perf_counter()
        self._observer.call(Trigger, '/benchmark_trivial/trigger', Trigger.Request())
        return time.perf_counter() - start

    def rcl_client(self, srv_type, name):
        """Return a client in C of a service (rcl_client.py) once the service is there."""
        client = RclClient(self._observer.node, srv_type, name)
        try:
            client.wait_for_service()
        except BaseException:
            client.destroy()
            raise
        return client

    def remove_spawned(self):
        """Remove every entity spawned since start-up (ResetSimulation, scope SPAWNED)."""
        from simulation_interfaces.srv import ResetSimulation
        self.call(ResetSimulation, '/reset_simulation',
                  ResetSimulation.Request(scope=ResetSimulation.Request.SCOPE_SPAWNED))

    def close(self):
        """Stop the executor thread and destroy both nodes."""
        self._executor_thread.stop()
        self.node.destroy_node()
        self._trivial.node.destroy_node()


def spawn_fields(index):
    """Return the name, namespace and pose of the index-th tinybot of a fleet, to spawn it."""
    from geometry_msgs.msg import PoseStamped
    name = fleet_names(index + 1)[index]
    pose = PoseStamped()
    pose.header.frame_id = 'world'
    pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = fleet_position(index)
    return {'name': name, 'entity_namespace': name, 'initial_pose': pose}


def tinybot_resource(*, by_uri=True):
    """Return tinybot as the standard's Resource: its package:// uri, or its URDF text."""
    from simulation_interfaces.msg import Resource
    if by_uri:
        return Resource(uri=TINYBOT_URI)
    return Resource(resource_string=read_model('tinybot'))


def single_spawn(index, resource):
    """Return the SpawnEntity service request of the index-th tinybot of a fleet."""
    from simulation_interfaces.srv import SpawnEntity
    return SpawnEntity.Request(uri=resource.uri, resource_string=resource.resource_string,
                               **spawn_fields(index))


def batch_spawn(count, resource):
    """Return the SpawnEntities request of a fleet of count tinybots."""
    from simulation_interfaces.msg import SpawnEntity
    from simulation_interfaces.srv import SpawnEntities
    return SpawnEntities.Request(spawn_requests=[
        SpawnEntity(entity_resource=resource, **spawn_fields(index)) for index in range(count)])


def world_description(urdf):
    """Return the MjSpec the world builds of a robot's URDF, as every spawn of it attaches."""
    from service_tutorial.sim.world import World
    return spawn_robot(World(), 'probe', urdf).description.spec


def bare_batch(robot_spec, count):
    """Return the wall time MuJoCo takes to attach count copies of a robot and recompile once."""
    bare = BareWorld('', [])
    root = robot_spec.worldbody.first_body()
    start = time.perf_counter()
    for index, name in enumerate(fleet_names(count)):
        frame = bare.spec.worldbody.add_frame(pos=fleet_position(index))
        frame.attach_body(root, name + '::', '')
    bare.model, bare.data = bare.spec.recompile(bare.model, bare.data)
    return time.perf_counter() - start


def spawn_rounds(world, config):
    """
    Time a batch spawn, MuJoCo's own batch, the same spawns one by one, and Trigger; in rounds.

    Each round: MuJoCo's batch on a bare spec (every other round, once the batch below is
    removed instead), a Trigger, SpawnEntities of the batch by uri, and a Trigger sent as soon
    as it answers: the world makes the robots' topics once the spawn is answered, and this
    Trigger is answered after them ('topics made', from the spawn request). Then the batch is
    removed, spawned again with the URDF text in each request
    ('by text') and removed; then the same tinybots are spawned by SpawnEntity one at a time,
    by uri (their total, until the last answer), and removed again.
    """
    from simulation_interfaces.srv import SpawnEntities, SpawnEntity
    robot_spec = world_description(read_model('tinybot'))
    batch = batch_spawn(config.standard_batch, tinybot_resource())
    by_text = batch_spawn(config.standard_batch, tinybot_resource(by_uri=False))
    singles = [single_spawn(index, tinybot_resource())
               for index in range(config.standard_batch)]
    samples = {'batch': [], 'bare batch': [], 'singles': [], 'trigger': [], 'topics made': [],
               'by text': []}
    for index in range(config.standard_rounds + 1):  # the first warms up
        # Which goes first alternates: a machine that slows down mid-round hits both.
        round_samples = {'bare batch': bare_batch(robot_spec, config.standard_batch)} \
            if index % 2 else {}
        round_samples['trigger'] = world.trigger()
        round_samples['batch'] = world.timed(SpawnEntities, '/spawn_entities', batch)
        round_samples['topics made'] = round_samples['batch'] + world.trigger()
        world.remove_spawned()
        if index % 2 == 0:
            round_samples['bare batch'] = bare_batch(robot_spec, config.standard_batch)
        round_samples['by text'] = world.timed(SpawnEntities, '/spawn_entities', by_text)
        world.remove_spawned()
        start = time.perf_counter()
        for request in singles:
            world.call(SpawnEntity, '/spawn_entity', request)
        round_samples['singles'] = time.perf_counter() - start
        world.remove_spawned()
        if index > 0:
            for key, value in round_samples.items():
                samples[key].append(value)
    return samples


def core_states(world, names):
    """Compute what GetEntitiesStates reports of names on a ROS-free World: poses, twists..."""
    accelerations = world.get_model_accelerations(names)
    return [(world.get_model_state(name), acceleration)
            for name, acceleration in zip(names, accelerations)]


def timed_in_c(client, layout, answered):
    """Return the wall time of one call from a C client; fail unless answered(its answer)."""
    start = time.perf_counter()
    client.call()
    seconds = time.perf_counter() - start
    if not answered(client.response(layout)):
        raise BenchmarkError(f'{client.name} answered the C client wrongly')
    return seconds


def states_rounds(world, config):
    """
    Time GetEntitiesStates of a spawned fleet, the same states on a World, and Trigger.

    The service and Trigger are called from a client in C (rcl_client.py), as a C or C++
    program calls them, and from rclpy's client, whose turning the answer into Python messages
    is a cost of its own.
    """
    from simulation_interfaces.srv import GetEntitiesStates, SpawnEntities
    from std_srvs.srv import Trigger
    count = config.standard_batch
    world.call(SpawnEntities, '/spawn_entities', batch_spawn(count, tinybot_resource()))
    core, names = core_fleet(count, driving=False), fleet_names(count)
    response = world.call(GetEntitiesStates, '/get_entities_states', GetEntitiesStates.Request())
    if list(response.entities) != names:
        raise BenchmarkError(f'get_entities_states listed {list(response.entities)}, not the '
                             f'{count} tinybots spawned')

    def all_states(answer):
        return (answer.result.result == RESULT_OK and answer.entities.size == count
                and answer.states.size == count)

    states_client = world.rcl_client(GetEntitiesStates, '/get_entities_states')
    try:
        trigger_client = world.rcl_client(Trigger, '/benchmark_trivial/trigger')
    except BaseException:
        states_client.destroy()
        raise
    samples = {'states': [], 'core states': [], 'trigger': [], 'rclpy states': [],
               'rclpy trigger': []}
    try:
        for index in range(config.standard_calls + 3):  # the first three warm up
            start = time.perf_counter()
            core_states(core, names)
            round_samples = {'core states': time.perf_counter() - start,
                             'states': timed_in_c(states_client, CStatesResponse,
                                                  all_states),
                             'trigger': timed_in_c(trigger_client, CTriggerResponse,
                                                   lambda answer: answer.success),
                             'rclpy states': world.timed(GetEntitiesStates,
                                                         '/get_entities_states',
                                                         GetEntitiesStates.Request()),
                             'rclpy trigger': world.trigger()}
            if index >= 3:
                for key, value in round_samples.items():
                    samples[key].append(value)
    finally:
        states_client.destroy()
        trigger_client.destroy()
    return samples


def angular_speed(world, name):
    """Return an entity's turning rate about z, in rad/s, through GetEntityState."""
    from simulation_interfaces.srv import GetEntityState
    response = world.call(GetEntityState, '/get_entity_state',
                          GetEntityState.Request(entity=name))
    return response.state.twist.angular.z


def start_driving(world, fleet, *, tries=10):
    """Command a paused world's fleet and step it until bot0 turns; fail if it never does."""
    from simulation_interfaces.srv import StepSimulation
    wait_until(lambda: all(p.get_subscription_count() > 0 for p in fleet.publishers),
               'the world did not subscribe to every cmd_vel')
    for _ in range(tries):
        # A command is taken at the world's next tick: one sent just before may be late.
        fleet.publish()
        world.call(StepSimulation, '/step_simulation', StepSimulation.Request(steps=STEP_WARM_UP))
        if angular_speed(world, fleet.names[0]) >= 0.8 * DRIVE_ANGULAR_Z:
            return
    raise BenchmarkError(f'{fleet.names[0]} does not turn on cmd_vel while stepped')


def step_rounds(observer, config):
    """
    Time StepSimulation of a driving fleet against bare mj_step of the same fleet, in rounds.

    Both fleets drive in circles: the node's on cmd_vel, the bare one as RawFleet sets it up.
    """
    from simulation_interfaces.srv import StepSimulation
    count, steps = config.standard_step_robots, config.standard_steps
    raw = RawFleet(count)
    world = StandardWorld(observer, fleet_parameters(count, 1.0))
    fleet = Fleet(observer, count)

    def bare_steps():
        start = time.perf_counter()
        mujoco.mj_step(raw.world.model, raw.world.data, steps)
        return time.perf_counter() - start

    try:
        start_driving(world, fleet)
        request = StepSimulation.Request(steps=steps)
        samples = {'stepping': [], 'bare steps': [], 'trigger': []}
        for index in range(config.standard_step_rounds + 1):  # the first warms up
            # Which goes first alternates: a machine that slows down mid-round hits both.
            round_samples = {'bare steps': bare_steps()} if index % 2 else {}
            round_samples['stepping'] = world.timed(StepSimulation, '/step_simulation', request)
            round_samples['trigger'] = world.trigger()
            if index % 2 == 0:
                round_samples['bare steps'] = bare_steps()
            if index > 0:
                for key, value in round_samples.items():
                    samples[key].append(value)
        if angular_speed(world, fleet.names[0]) < 0.8 * DRIVE_ANGULAR_Z:
            raise BenchmarkError(f'{fleet.names[0]} stopped turning during the measurement')
        samples.update(calls_during_stepping(observer, world, config.standard_calls))
        return samples
    finally:
        fleet.destroy()
        world.close()


def calls_during_stepping(observer, world, count):
    """
    Time get_model_list and Trigger, in turns, while one StepSimulation of LONG_STEPPING steps.

    Return the times in s by name ('during stepping', 'trigger during stepping'). Playing ends
    the stepping (set_simulation_state); the world is paused again afterwards.
    """
    from simulation_interfaces.msg import SimulationState
    from simulation_interfaces.srv import SetSimulationState, StepSimulation
    from srv_interfaces.srv import GetModelList
    stepping = observer.call_async(StepSimulation, '/step_simulation',
                                   StepSimulation.Request(steps=LONG_STEPPING))
    samples = {'during stepping': [], 'trigger during stepping': []}
    observer.wait_for_service(GetModelList, '/mujoco/get_model_list')
    try:
        for _ in range(count):
            start = time.perf_counter()
            answer = observer.call(GetModelList, '/mujoco/get_model_list', GetModelList.Request())
            samples['during stepping'].append(time.perf_counter() - start)
            if not answer.success:
                raise BenchmarkError(f'get_model_list failed: {answer.status_message}')
            samples['trigger during stepping'].append(world.trigger())
            if stepping.done():
                raise BenchmarkError(f'StepSimulation ended during the calls: {stepping.result()}')
    finally:
        for target in (SimulationState.STATE_PLAYING, SimulationState.STATE_PAUSED):
            world.call(SetSimulationState, '/set_simulation_state', SetSimulationState.Request(
                state=SimulationState(state=target)))
    wait_until(stepping.done, 'StepSimulation did not end when the world played')
    return samples


def _row(figure, rounds, measured, reference, trigger, limit):
    """Return a row of the table; a row without a limit (None) only informs."""
    within = None if limit is None else measured <= limit
    return [figure, rounds, measured, reference, trigger, limit, within]


def standard_table(observer, config):
    """SpawnEntities, StepSimulation and GetEntitiesStates against their limits."""
    from rclpy.serialization import serialize_message
    count = config.standard_batch
    with quiet_console(config.log_path):
        world = StandardWorld(observer, {'models': [], 'scenery': ''})
        try:
            # Short calls whose answers come while the world goes on working (see
            # prompt_thread_switches); one stepping call of a second waits at most 5 ms once.
            with prompt_thread_switches():
                spawning = spawn_rounds(world, config)
                states = states_rounds(world, config)
        finally:
            world.close()
        stepping = step_rounds(observer, config)
    table = Table('standard_interfaces', 'The standard simulation interfaces against their '
                  'limits (ms)', [
                      ('figure', ''), ('rounds', 'd'), ('service p50', '.2f'),
                      ('reference p50', '.2f'), ('Trigger p50', '.3f'), ('limit', '.2f'),
                      ('within', '')])
    batch, bare = median_ms(spawning['batch']), median_ms(spawning['bare batch'])
    singles, trigger = median_ms(spawning['singles']), median_ms(spawning['trigger'])
    rounds = len(spawning['batch'])
    topics_made = median_ms(spawning['topics made'])
    by_text = median_ms(spawning['by text'])
    text_kb = len(serialize_message(batch_spawn(count, tinybot_resource(by_uri=False)))) / 1024
    table.rows.append(_row(f'SpawnEntities of {count} tinybots by uri <= {BATCH_LIMIT:g} x MuJoCo '
                           f'batch + {TRIGGERS_ALLOWED:g} x Trigger', rounds, batch, bare,
                           trigger, BATCH_LIMIT * bare + TRIGGERS_ALLOWED * trigger))
    table.rows.append(_row(f'SpawnEntities of {count} tinybots <= 1/{SINGLES_FACTOR:g} of {count} '
                           'SpawnEntity calls',
                           rounds, batch, singles, trigger, singles / SINGLES_FACTOR))
    trigger = median_ms(stepping['trigger'])
    bare = 1e3 * min(stepping['bare steps'])
    table.rows.append(_row(f'StepSimulation of {config.standard_steps} steps, '
                           f'{config.standard_step_robots} tinybots <= {STEP_LIMIT:g} x bare '
                           f'mj_step + {TRIGGERS_ALLOWED:g} x Trigger (best of rounds)',
                           len(stepping['stepping']), 1e3 * min(stepping['stepping']), bare,
                           trigger, STEP_LIMIT * bare + TRIGGERS_ALLOWED * trigger))
    during = stepping['during stepping']
    table.rows.append(_row(f'get_model_list p99 while StepSimulation steps <= '
                           f'{DURING_STEPPING_LIMIT:g} ms', len(during), percentiles(during)[2],
                           median_ms(during), median_ms(stepping['trigger during stepping']),
                           DURING_STEPPING_LIMIT))
    trigger = median_ms(states['trigger'])
    core = median_ms(states['core states'])
    table.rows.append(_row(f'GetEntitiesStates of {count} entities <= core + '
                           f'{TRIGGERS_ALLOWED:g} x Trigger', len(states['states']),
                           median_ms(states['states']), core, trigger,
                           core + TRIGGERS_ALLOWED * trigger))
    rclpy_extra = median_ms(states['rclpy states']) - median_ms(states['states'])
    table.rows.append(_row(f"GetEntitiesStates of {count} entities from rclpy's client, "
                           'Trigger too (no limit)', len(states['rclpy states']),
                           median_ms(states['rclpy states']), core,
                           median_ms(states['rclpy trigger']), None))
    table.note = (
        'reference: what the service is compared with, taken in turns with it, round by round. '
        f'SpawnEntities: from request to answer, each tinybot by its uri ({TINYBOT_URI}; '
        f'with the URDF text in each request instead, the call took {by_text:.0f} ms, its '
        f'{text_kb:.0f} KB carried by the middleware); '
        "MuJoCo's own path for the same batch on a "
        "bare MjSpec (spawn_cost.py's BareWorld): attach_body of the robot the world builds "
        'of the URDF (its links, visuals, sensors and actuators; built once, as the world '
        'builds each distinct URDF text once) for each, one recompile; limit '
        f'{BATCH_LIMIT} x reference + {TRIGGERS_ALLOWED:g} x Trigger. The topics of the '
        'robots are made once the spawn is '
        f'answered: every topic of the {count} tinybots was made {topics_made:.0f} ms after the '
        f'request (p50), {topics_made - batch:.0f} ms of rclpy and the middleware making '
        f'{TOPICS_PER_TINYBOT * count} topics. Against {count} SpawnEntity calls (their total '
        'until the last answer; the executor makes the topics of each before it serves the next '
        f'call): the batch must take at most 1/{SINGLES_FACTOR:g} of their total. '
        'StepSimulation: from request to answer, the world paused and its robots driving on '
        'cmd_vel; reference: one '
        'bare mj_step call of as many steps on the same fleet, compiled in this process and '
        f'driving too; best of {len(stepping["stepping"])} rounds each; limit {STEP_LIMIT} x '
        'reference + '
        f'{TRIGGERS_ALLOWED:g} x Trigger. GetEntitiesStates: every entity, no filter; '
        "reference: the core's cost, the same accelerations, poses and twists read from a "
        f'ROS-free World holding the same fleet; limit reference + {TRIGGERS_ALLOWED:g} x '
        'Trigger, the call and the Trigger both from a client in C (rcl_client.py: librcl '
        'through ctypes, the answer taken into C structs as a C or C++ client takes it), so '
        "that the limit holds the world to its own cost; rclpy's client, in the row without a "
        f'limit, spends {rclpy_extra:.1f} ms more on the same call, turning the answer into '
        f'{count} nested Python messages. '
        "Trigger: the trivial service on the world's executor. The world attaches a batch in "
        'groups of five through a small spec of their own (sim/attachment.py), where the '
        'reference attaches each robot to the whole spec. SpawnEntities and GetEntitiesStates '
        'rounds: the world and its client share this interpreter, and a thread waiting for the '
        f"GIL gets it after {1e3 * THREAD_SWITCH_INTERVAL:g} ms instead of Python's 5 ms "
        '(harness.prompt_thread_switches), as a client in a process of its own never waits '
        'for it; StepSimulation rounds keep the 5 ms.')
    return table
