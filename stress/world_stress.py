"""
Long-run and concurrency stress of the MuJoCo world node, as separate processes meet it.

The world runs as the installed mujoco_world console script in a process of its own; clients
are nodes in this process, each on an executor thread of its own, plus client processes that
are killed in the middle of a call. Phases:

- same name: every client spawns the same name at the same moment; exactly one may succeed;
- mixed: every client spawns, deletes, reads and sets states, resets and lists the world for
  --seconds; each call must be answered, with nothing but the refusals it asked for, and at
  the end the world must hold exactly the models the clients believe they own, all finite;
- killed clients: a client process sends a spawn and is killed with SIGKILL before the answer;
  the world must go on answering and stepping;
- cycles: --cycles spawn/delete cycles; the world's memory (RSS) at the end must be within
  10 % of what it was after the first 100, and the last 100 cycles no slower than the first
  100 by more than 10 %;
- sensor storm: --storm-robots tinybots with the largest camera and laser the world accepts,
  measuring at every physics step, all listened to (by a process of its own), while every
  client lists the world and reads a storm robot's state for --storm-seconds; every call must
  be answered within
  CALL_TIMEOUT, /clock must never stand still for more than 1 s of wall time, and the p99
  answer time must stay within --storm-p99-limit (the issue's target, 0.2 s).

It prints a summary table and exits with status 1 if a property fails. Run it with
scripts/stress [--phases P,...] [--seconds S] [--cycles N] [--clients N] [--storm-seconds S]
[--storm-robots N] [--storm-p99-limit S] [--real-time-factor F].
"""

import argparse
import collections
import functools
import math
import multiprocessing
import os
import random
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import textwrap
import threading
import time

from service_tutorial.testing.isolation import isolate_ros_graph

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CALL_TIMEOUT = 10.0
# Cycles whose time and memory are compared, at the start and at the end of the cycle phase.
WINDOW = 100
ALLOWED_DRIFT = 0.10
MIXED_OPERATIONS = (('spawn', 4), ('delete', 3), ('get_state', 4), ('set_state', 3),
                    ('bad_request', 2), ('list_models', 2), ('reset_world', 1))
# Models one mixed-phase client keeps at most; beyond, its spawns turn into deletes.
MAX_OWNED = 6
PHASES = ('same-name', 'mixed', 'killed', 'cycles', 'storm')
# The target for the p99 answer time while the storm robots are listened to, in s.
STORM_P99_TARGET = 0.2
# The longest /clock may stand still during the storm, in s of wall time.
CLOCK_STILL_LIMIT = 1.0
# Wall time the clients make the storm's calls before the storm robots come, for comparison.
CALM_SECONDS = 5.0
# Slowest storm calls named in the summary.
SLOWEST_SHOWN = 5


def client_qos():
    """Return the QoS of the stress clients: rclpy's for services, with a deeper history."""
    from rclpy.qos import qos_profile_services_default, QoSProfile
    profile = QoSProfile(**{name: getattr(qos_profile_services_default, name) for name in (
        'history', 'reliability', 'durability')}, depth=100)
    return profile


def world_command(real_time_factor):
    """Return the command line that starts the world node as users start it."""
    executable = shutil.which('mujoco_world')
    command = [executable] if executable else [sys.executable, '-m',
                                               'service_tutorial.world_node.node']
    return command + ['--ros-args', '-p', f'real_time_factor:={real_time_factor}',
                      '--log-level', 'warn']


def rss_bytes(pid):
    """Return the resident set size of a process, in bytes."""
    with open(f'/proc/{pid}/status') as status:
        for line in status:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) * 1024
    raise RuntimeError(f'no VmRSS for process {pid}')


def read_model(name):
    """Return the URDF text of one of the package's models."""
    from ament_index_python.packages import get_package_share_directory
    path = os.path.join(get_package_share_directory('service_tutorial'), 'models', name + '.urdf')
    with open(path) as model_file:
        return model_file.read()


class Tally:
    """Calls made and their outcomes, by phase; thread safe."""

    def __init__(self):
        self._lock = threading.Lock()
        self.calls = collections.Counter()
        self.outcomes = collections.defaultdict(collections.Counter)
        self.examples = {}

    def count(self, phase, outcome, detail=''):
        """Count one call of a phase: 'ok', 'refused as asked', or a kind of failure."""
        with self._lock:
            self.calls[phase] += 1
            self.outcomes[phase][outcome] += 1
            if outcome not in ('ok', 'refused as asked'):
                self.examples.setdefault((phase, outcome), detail)

    def failures(self):
        """Return {(phase, kind): count} of every outcome that is a failure."""
        return {(phase, kind): number for phase, counter in self.outcomes.items()
                for kind, number in counter.items() if kind not in ('ok', 'refused as asked')}


class WorldClient:
    """A client node on an executor thread of its own, calling the world's services."""

    def __init__(self, name):
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        self.node = Node(name)
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self.executor.spin, daemon=True)
        self.thread.start()
        self.clients = {}

    def call(self, srv_type, service, request, timeout=CALL_TIMEOUT):
        """Return the response of /mujoco/<service>, or None if it did not come in time."""
        client = self.clients.get(service)
        if client is None:
            client = self.node.create_client(srv_type, '/mujoco/' + service,
                                             qos_profile=client_qos())
            if not client.wait_for_service(timeout_sec=timeout):
                return None
            self.clients[service] = client
        answered = threading.Event()
        future = client.call_async(request)
        future.add_done_callback(lambda _: answered.set())
        if not answered.wait(timeout):
            future.cancel()
            return None
        return future.result()

    def close(self):
        """Stop the executor and destroy the node."""
        self.executor.shutdown(timeout_sec=5.0)
        self.thread.join(timeout=5.0)
        self.node.destroy_node()


class Services:
    """Request builders and calls for the world's services."""

    def __init__(self, client):
        from srv_interfaces.srv import DeleteModel, GetModelList, GetModelState
        from srv_interfaces.srv import SetModelState, SpawnModel
        from std_srvs.srv import Empty
        self.client = client
        self.types = {'spawn_urdf_model': SpawnModel, 'delete_model': DeleteModel,
                      'get_model_list': GetModelList, 'get_model_state': GetModelState,
                      'set_model_state': SetModelState, 'reset_world': Empty,
                      'reset_simulation': Empty}
        # Each type's support is loaded on first use, and not safely from several threads at
        # once: the clients of the same-name phase, started together, raised TypeError
        # ('NoneType' is not a 'capsule') converting their first request.
        from rclpy.type_support import check_for_type_support
        for srv_type in self.types.values():
            check_for_type_support(srv_type)

    def call(self, service, **fields):
        """Call a world service with the given request fields."""
        srv_type = self.types[service]
        return self.client.call(srv_type, service, srv_type.Request(**fields))

    def spawn(self, name, xml, x=0.0, y=0.0, z=0.0, namespace=''):
        """Spawn a model at a place on the ground."""
        from geometry_msgs.msg import Pose
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = x, y, z
        pose.orientation.w = 1.0
        return self.call('spawn_urdf_model', model_name=name, model_xml=xml,
                         robot_namespace=namespace, initial_pose=pose)

    def models(self):
        """Return the model names, or None if the world did not answer."""
        response = self.call('get_model_list')
        return None if response is None else list(response.model_names)

    def finite_state(self, name):
        """Return whether a model's state came back, successfully and finite."""
        response = self.call('get_model_state', model_name=name)
        if response is None or not response.success:
            return False
        p, q, t = response.pose.position, response.pose.orientation, response.twist
        return all(math.isfinite(value) for value in (
            p.x, p.y, p.z, q.w, q.x, q.y, q.z, t.linear.x, t.linear.y, t.linear.z,
            t.angular.x, t.angular.y, t.angular.z))


def judge(tally, phase, response, expect_success=True, expect_message=''):
    """Count a response as 'ok', 'refused as asked', or the kind of failure it is."""
    if response is None:
        tally.count(phase, 'no answer in time')
    elif response.success and expect_success:
        tally.count(phase, 'ok')
    elif response.success:
        tally.count(phase, 'succeeded, should have been refused', expect_message)
    elif expect_success:
        tally.count(phase, 'refused unexpectedly', response.status_message)
    elif expect_message in response.status_message:
        tally.count(phase, 'refused as asked')
    else:
        tally.count(phase, 'refused for another reason', response.status_message)
    return response


def same_name_phase(clients, tally, models):
    """Every client spawns the same name at once: exactly one must succeed."""
    start = threading.Barrier(len(clients))
    responses = [None] * len(clients)

    def spawn(index):
        start.wait()
        responses[index] = clients[index].spawn('contested', models['r2d2'], x=5.0)

    threads = [threading.Thread(target=spawn, args=(index,)) for index in range(len(clients))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    winners = [response for response in responses if response is not None and response.success]
    for response in responses:
        if response is None:
            tally.count('same name', 'no answer in time')
        elif response.success:
            tally.count('same name', 'ok')
        elif "a model named 'contested' already exists" in response.status_message:
            tally.count('same name', 'refused as asked')
        else:
            tally.count('same name', 'refused for another reason', response.status_message)
    if len(winners) != 1:
        tally.count('same name', f'{len(winners)} spawns succeeded, not 1')
    judge(tally, 'same name', clients[0].call('delete_model', model_name='contested'))


class MixedClient:
    """One client of the mixed phase: its own models, and what it believes the world holds."""

    def __init__(self, index, services, tally, models, seed):
        self.index = index
        self.services = services
        self.tally = tally
        self.models = models
        self.random = random.Random(seed)
        self.owned = {}  # name -> (x, y) of its spot
        self.spawned = 0
        operations, weights = zip(*MIXED_OPERATIONS)
        self.operations, self.weights = operations, weights

    def spot(self):
        """Return a free place for a new model, in this client's own strip of the floor."""
        taken = set(self.owned.values())
        return next(spot for spot in ((2.0 + 2.0 * slot, -20.0 + 5.0 * self.index)
                                      for slot in range(MAX_OWNED + 1)) if spot not in taken)

    def run(self, deadline, stop):
        """Make calls until the deadline, or until stop is set, then return."""
        while time.monotonic() < deadline and not stop.is_set():
            operation = self.random.choices(self.operations, self.weights)[0]
            getattr(self, operation)()

    def spawn(self):
        """Spawn R2-D2 or a tinybot with topics of its own, at a free spot."""
        if len(self.owned) >= MAX_OWNED:
            return self.delete()
        self.spawned += 1
        name = f'client{self.index}_{self.spawned}'
        x, y = self.spot()
        if self.random.random() < 0.5:
            response = self.services.spawn(name, self.models['tinybot'], x, y, namespace=name)
        else:
            response = self.services.spawn(name, self.models['r2d2'], x, y)
        if judge(self.tally, 'mixed', response) is not None and response.success:
            self.owned[name] = (x, y)

    def delete(self):
        """Delete one of its models, or ask to delete one that does not exist."""
        if self.owned and self.random.random() < 0.8:
            name = self.random.choice(sorted(self.owned))
            response = judge(self.tally, 'mixed',
                             self.services.call('delete_model', model_name=name))
            if response is not None and response.success:
                del self.owned[name]
        else:
            judge(self.tally, 'mixed',
                  self.services.call('delete_model', model_name=f'ghost{self.index}'),
                  expect_success=False, expect_message=f"no model named 'ghost{self.index}'")

    def get_state(self):
        """Read the state of one of its models, or tinybot's."""
        name = self.random.choice(sorted(self.owned) + ['tinybot'])
        if self.services.finite_state(name):
            self.tally.count('mixed', 'ok')
        else:
            self.tally.count('mixed', 'state missing or not finite', name)

    def set_state(self):
        """Move one of its models back above its spot, turning."""
        from geometry_msgs.msg import Pose, Twist
        if not self.owned:
            return self.get_state()
        name = self.random.choice(sorted(self.owned))
        x, y = self.owned[name]
        pose, twist = Pose(), Twist()
        pose.position.x, pose.position.y, pose.position.z = x, y, 0.3
        pose.orientation.w = 1.0
        twist.angular.z = self.random.uniform(-2.0, 2.0)
        judge(self.tally, 'mixed', self.services.call('set_model_state', model_name=name,
                                                      pose=pose, twist=twist))

    def bad_request(self):
        """Send a request the world must refuse, and check that it names the cause."""
        kind = self.random.randrange(3)
        if kind == 0:
            response = self.services.spawn(f'broken{self.index}', '<robot name="b"><link')
            judge(self.tally, 'mixed', response, False, 'does not parse as XML')
        elif kind == 1:
            response = self.services.spawn('tinybot', self.models['r2d2'], 9.0, 9.0)
            judge(self.tally, 'mixed', response, False, "a model named 'tinybot' already exists")
        else:
            response = self.services.spawn(f'nan{self.index}', self.models['r2d2'], math.nan)
            judge(self.tally, 'mixed', response, False, 'position contains NaN')

    def list_models(self):
        """List the models: every model this client owns must be there."""
        models = self.services.models()
        if models is None:
            self.tally.count('mixed', 'no answer in time')
        elif set(self.owned) <= set(models):
            self.tally.count('mixed', 'ok')
        else:
            self.tally.count('mixed', 'own model missing from the list',
                             sorted(set(self.owned) - set(models)))

    def reset_world(self):
        """Put every model back at its spawn pose."""
        response = self.services.call('reset_world')
        self.tally.count('mixed', 'no answer in time' if response is None else 'ok')


def where_stuck(thread):
    """Return the innermost frames of a thread, to tell where it hangs."""
    frame = sys._current_frames().get(thread.ident)
    places = []
    while frame is not None and len(places) < 4:
        places.append(f'{os.path.basename(frame.f_code.co_filename)}:{frame.f_lineno} '
                      f'{frame.f_code.co_name}')
        frame = frame.f_back
    return ' < '.join(places)


def mixed_phase(clients, tally, models, seconds, world):
    """Run every client's mixed calls for the given time; return the problems at the end."""
    mixed = [MixedClient(index, services, tally, models, seed=index)
             for index, services in enumerate(clients)]
    deadline = time.monotonic() + seconds
    stop = threading.Event()
    threads = [threading.Thread(target=client.run, args=(deadline, stop), daemon=True)
               for client in mixed]
    for thread in threads:
        thread.start()
    while any(thread.is_alive() for thread in threads):
        if world.poll() is not None or time.monotonic() > deadline + 3 * CALL_TIMEOUT:
            stop.set()
        threads[0].join(timeout=0.5)
        threads = [thread for thread in threads if thread.is_alive()]
        if stop.is_set() and time.monotonic() > deadline + 6 * CALL_TIMEOUT:
            return [f'{len(threads)} clients hung: ' + '; '.join(
                where_stuck(thread) for thread in threads)], 0
    problems = []
    believed = {'tinybot'}.union(*(client.owned for client in mixed))
    listed = clients[0].models()
    if listed is None or set(listed) != believed or len(listed) != len(set(listed)):
        problems.append(f'the world lists {sorted(listed or [])}, the clients believe '
                        f'{sorted(believed)}')
    not_finite = [name for name in sorted(believed) if not clients[0].finite_state(name)]
    if not_finite:
        problems.append(f'states missing or not finite: {not_finite}')
    for client in mixed:
        for name in client.owned:
            judge(tally, 'mixed', clients[0].call('delete_model', model_name=name))
    return problems, len(believed) - 1


KILLED_CLIENT = textwrap.dedent("""
    import sys
    import rclpy
    from geometry_msgs.msg import Pose
    from srv_interfaces.srv import SpawnModel
    rclpy.init()
    node = rclpy.create_node('doomed_client')
    client = node.create_client(SpawnModel, '/mujoco/spawn_urdf_model')
    client.wait_for_service(timeout_sec=10.0)
    pose = Pose()
    pose.position.x, pose.orientation.w = -5.0, 1.0
    request = SpawnModel.Request(model_name=sys.argv[1], model_xml=sys.stdin.read(),
                                 initial_pose=pose)
    client.call_async(request)
    print('sent', flush=True)
    rclpy.spin(node)
""")


def killed_client_phase(client, tally, models, world, rounds=5):
    """Kill client processes in the middle of a spawn; the world must not notice."""
    # A big model_xml keeps the request on the wire while the client is killed.
    payload = models['r2d2'].replace('</robot>', '<!--' + 'x' * 4_000_000 + '--></robot>')
    arrived = []
    for round_ in range(rounds):
        name = f'orphan{round_}'
        doomed = subprocess.Popen([sys.executable, '-c', KILLED_CLIENT, name],
                                  stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        doomed.stdin.write(payload)
        doomed.stdin.close()
        doomed.stdout.readline()
        # From at once to well after the world has answered a client that is gone.
        time.sleep(0.05 * round_)
        doomed.send_signal(signal.SIGKILL)
        doomed.wait()
        models_now = client.models()
        if models_now is None:
            tally.count('killed clients', 'no answer in time')
            continue
        tally.count('killed clients', 'ok')
        if name in models_now:
            arrived.append(name)
            judge(tally, 'killed clients', client.call('delete_model', model_name=name))
        if not client.finite_state('tinybot'):
            tally.count('killed clients', 'state missing or not finite', 'tinybot')
        if world.poll() is not None:
            tally.count('killed clients', 'world process died')
            break
    return arrived


def cycles_phase(client, tally, models, world_pid, cycles):
    """Spawn and delete a robot with topics of its own, cycles times; return the figures."""
    durations, memory = [], {}
    for cycle in range(cycles):
        start = time.perf_counter()
        spawned = judge(tally, 'cycles', client.spawn('cycler', models['tinybot'], 3.0, 3.0,
                                                      namespace='cycler'))
        judge(tally, 'cycles', client.call('delete_model', model_name='cycler'))
        durations.append(time.perf_counter() - start)
        if spawned is None:
            break
        if cycle + 1 in (WINDOW, cycles):
            memory[cycle + 1] = rss_bytes(world_pid)
    figures = {'cycles': len(durations), 'rss': memory}
    if len(durations) >= 2 * WINDOW:
        figures['first'] = statistics.median(durations[:WINDOW])
        figures['last'] = statistics.median(durations[-WINDOW:])
    return figures


def replace_once(text, old, new):
    """Return text with old replaced by new, refusing a model where old is not there once."""
    if text.count(old) != 1:
        raise RuntimeError(f'tinybot.urdf holds {text.count(old)} times {old!r}, not once: '
                           'the storm robot cannot be built from it')
    return text.replace(old, new)


def storm_robot(tinybot, rate):
    """Return tinybot with the largest camera and laser the world accepts, measuring at rate."""
    from service_tutorial.sim.plugins.camera_sensor import MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE
    from service_tutorial.sim.plugins.ray_sensor import MAX_SCAN_READINGS
    side = min(math.isqrt(MAX_IMAGE_PIXELS), MAX_IMAGE_SIDE)
    sensors = {'width': side, 'height': side, 'readings': MAX_SCAN_READINGS, 'rate': rate}
    xml = tinybot
    # The camera's size and rate, then the laser's readings and rate.
    for tag, old, new in (('width', 320, side), ('height', 240, side), ('update_rate', 10, rate),
                          ('samples', 360, MAX_SCAN_READINGS), ('update_rate', 5, rate)):
        xml = replace_once(xml, f'<{tag}>{old}</{tag}>', f'<{tag}>{new:g}</{tag}>')
    return xml, sensors


def physics_rate(client):
    """Return the world's physics steps per second of simulation time, from its timestep."""
    from rcl_interfaces.srv import GetParameters
    response = client.call(GetParameters, 'get_parameters', GetParameters.Request(
        names=['timestep']))
    if response is None or len(response.values) != 1 or response.values[0].double_value <= 0.0:
        raise RuntimeError('the world did not tell its timestep')
    return 1.0 / response.values[0].double_value


def nearest_rank(ordered, fraction):
    """Return the value at a fraction of an ordered list, by nearest rank."""
    return ordered[max(0, math.ceil(fraction * len(ordered)) - 1)]


def listen_to_storm(robots, counts, stop):
    """In a process of its own, count each storm robot's images and scans until stop is set."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from sensor_msgs.msg import Image, LaserScan
    rclpy.init()
    node = rclpy.create_node('storm_listener')
    try:
        for index, robot in enumerate(robots):
            for offset, (msg_type, topic) in enumerate(((Image, 'camera/image_raw'),
                                                        (LaserScan, 'scan'))):
                # Raw: counted, not turned into Python messages.
                node.create_subscription(msg_type, f'/{robot}/{topic}', functools.partial(
                    count_message, counts, 2 * index + offset), 10, raw=True)
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        while not stop.is_set():
            executor.spin_once(timeout_sec=0.1)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


def count_message(counts, slot, _):
    """Count one message in a slot of a shared array."""
    with counts.get_lock():
        counts[slot] += 1


class StormListener:
    """
    Every image and scan of the storm robots, listened to by a process of its own; /clock here.

    A separate process, as a viewer or a recorder would be: 36 MB of images a second received
    in the callers' own process would hold up their answers there, not in the world.
    """

    def __init__(self, robots):
        """Start the listening process; listen to /clock on a node of its own."""
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from rosgraph_msgs.msg import Clock
        self.robots = robots
        self.clock = WorldClient('storm_clock')
        self.ticks = []  # (wall time, simulation time) of each /clock message
        context = multiprocessing.get_context('spawn')
        self._counts = context.Array('q', 2 * len(robots))
        self._stop = context.Event()
        self._process = context.Process(target=listen_to_storm, daemon=True,
                                        args=(robots, self._counts, self._stop))
        self._process.start()
        self.subscription = self.clock.node.create_subscription(
            Clock, '/clock', self._tick, QoSProfile(
                depth=1, reliability=ReliabilityPolicy.RELIABLE,
                durability=DurabilityPolicy.TRANSIENT_LOCAL))

    def _tick(self, msg):
        self.ticks.append((time.monotonic(), msg.clock.sec + 1e-9 * msg.clock.nanosec))

    def counts(self):
        """Return the messages received so far, by robot and kind."""
        with self._counts.get_lock():
            values = list(self._counts)
        return collections.Counter({(robot, kind): values[2 * index + offset]
                                    for index, robot in enumerate(self.robots)
                                    for offset, kind in enumerate(('images', 'scans'))})

    def clock_figures(self, start, end):
        """Return the simulation time passed and /clock's longest standstill in [start, end]."""
        ticks = [tick for tick in list(self.ticks) if start <= tick[0] <= end]
        if not ticks:
            return 0.0, end - start
        still, moved_at, last = 0.0, start, ticks[0][1]
        for wall, sim in ticks[1:]:
            if sim > last:
                still, moved_at, last = max(still, wall - moved_at), wall, sim
        return ticks[-1][1] - ticks[0][1], max(still, end - moved_at)

    def close(self):
        """Stop listening."""
        self._stop.set()
        self._process.join(timeout=10.0)
        if self._process.is_alive():
            self._process.kill()
        self.clock.close()


def storm_caller(index, services, tally, robots, deadline, answers):
    """List the world and read a storm robot's state in turn until the deadline."""
    calls = 0
    while time.monotonic() < deadline:
        robot = robots[(index + calls // 2) % len(robots)]
        service = 'get_model_list' if calls % 2 == 0 else 'get_model_state'
        fields = {} if service == 'get_model_list' else {'model_name': robot}
        start = time.monotonic()
        response = services.call(service, **fields)
        answered = time.monotonic()
        calls += 1
        if response is None:
            tally.count('storm', 'no answer in time', f'{service} at {start:.1f}')
            continue
        answers.append((answered - start, service, start))
        if not response.success:
            tally.count('storm', 'refused unexpectedly', response.status_message)
        elif service == 'get_model_list' and not set(robots) <= set(response.model_names):
            tally.count('storm', 'storm robot missing from the list',
                        sorted(set(robots) - set(response.model_names)))
        elif service == 'get_model_state' and not all(math.isfinite(value) for value in (
                response.pose.position.x, response.pose.position.y, response.pose.position.z)):
            tally.count('storm', 'state missing or not finite', robot)
        else:
            tally.count('storm', 'ok')


def call_window(clients, tally, robots, seconds, figures):
    """Have every client call for seconds; return the sorted answers, the start and the end."""
    answers = []
    start = time.monotonic()
    threads = [threading.Thread(target=storm_caller, daemon=True, args=(
        index, services, tally, robots, start + seconds, answers))
        for index, services in enumerate(clients)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=seconds + 2 * CALL_TIMEOUT)
    if any(thread.is_alive() for thread in threads):
        figures['problems'].append('storm callers hung: ' + '; '.join(
            where_stuck(thread) for thread in threads if thread.is_alive()))
    return sorted(answers), start, time.monotonic()


def storm_phase(clients, tally, models, arguments, world):
    """Listen to storm robots' largest sensors while every client calls; return the figures."""
    rate = physics_rate(clients[0].client)
    xml, sensors = storm_robot(models['tinybot'], rate)
    before = clients[0].models()
    figures = {'sensors': sensors, 'problems': []}
    # The same calls first without the storm robots, for comparison; each client finds its
    # services before.
    for services in clients:
        services.models()
    figures['calm'] = call_window(clients, tally, ['tinybot'],
                                  min(CALM_SECONDS, arguments.storm_seconds), figures)[0]
    robots = []
    for index in range(arguments.storm_robots):
        robot = f'storm{index}'
        spawned = judge(tally, 'storm', clients[0].spawn(
            robot, xml, -4.0, 3.0 * (index - (arguments.storm_robots - 1) / 2.0),
            namespace=robot))
        if spawned is None or not spawned.success:
            figures['problems'].append(f'storm robot {robot} could not be spawned')
            break
        robots.append(robot)
    figures['robots'] = robots
    if not robots:
        raise RuntimeError('no storm robot could be spawned: ' + '; '.join(figures['problems']))
    listener = StormListener(robots)
    try:
        # The sensors start measuring once the world sees they are listened to.
        started = time.monotonic()
        while (time.monotonic() < started + CALL_TIMEOUT and world.poll() is None
               and sum(1 for received in listener.counts().values() if received)
               < 2 * len(robots)):
            time.sleep(0.05)
        figures['first_messages'] = time.monotonic() - started
        counts_at_start = listener.counts()
        answers, start, end = call_window(clients, tally, robots, arguments.storm_seconds,
                                          figures)
        received = listener.counts() - counts_at_start
        simulated, still = listener.clock_figures(start, end)
    finally:
        for robot in robots:
            judge(tally, 'storm', clients[0].call('delete_model', model_name=robot))
        listener.close()
    figures.update(seconds=end - start, simulated=simulated, still=still,
                   started=start, answers=answers, received={
                       (robot, kind): received[robot, kind] / (end - start)
                       for robot in robots for kind in ('images', 'scans')})
    silent = [f'{robot} {kind}' for (robot, kind), rate in figures['received'].items()
              if rate == 0.0]
    if silent:
        figures['problems'].append(f'nothing received during the storm from {silent}')
    if still > CLOCK_STILL_LIMIT:
        figures['problems'].append(f'/clock stood still for {still:.2f} s of wall time during '
                                   f'the storm (at most {CLOCK_STILL_LIMIT:g} s)')
    if answers:
        p99 = nearest_rank(answers, 0.99)[0]
        if p99 > arguments.storm_p99_limit:
            figures['problems'].append(f'storm p99 answer time {p99:.3f} s is above '
                                       f'--storm-p99-limit {arguments.storm_p99_limit:g} s')
    else:
        figures['problems'].append('no storm call was answered')
    after = clients[0].models()
    if after != before or not clients[0].finite_state('tinybot'):
        figures['problems'].append(f'after the storm the world lists {after}, not {before}, '
                                   "or did not give tinybot's state")
    return figures


def answer_times(answers):
    """Return the count and the p50, p99 and max answer times of sorted answers, in words."""
    p50, p99 = (nearest_rank(answers, fraction)[0] for fraction in (0.5, 0.99))
    return (f'{len(answers)} calls answered: p50 {p50 * 1e3:.1f} ms, p99 {p99 * 1e3:.1f} ms, '
            f'max {answers[-1][0] * 1e3:.1f} ms')


def print_storm(storm, clients):
    """Print the figures of the sensor storm."""
    sensors = storm['sensors']
    print(f'\nsensor storm: {len(storm["robots"])} robots ({", ".join(storm["robots"])}), each '
          f'a {sensors["width"]}x{sensors["height"]} camera and a {sensors["readings"]}-reading '
          f'laser at {sensors["rate"]:g} Hz (every physics step), all listened to; {clients} '
          f'clients calling for {storm["seconds"]:.1f} s (first messages after '
          f'{storm["first_messages"]:.1f} s)')
    if storm['calm']:
        print(f'  before the storm robots came, {answer_times(storm["calm"])}')
    answers = storm['answers']
    if answers:
        p99 = nearest_rank(answers, 0.99)[0]
        print(f'  during the storm, {answer_times(answers)}')
        print(f'  p99 {p99:.3f} s (target {STORM_P99_TARGET:g} s): '
              f'{"holds" if p99 <= STORM_P99_TARGET else "does not hold"}')
        slowest = ', '.join(f'{service} {elapsed * 1e3:.0f} ms at {at - storm["started"]:.1f} s'
                            for elapsed, service, at in reversed(answers[-SLOWEST_SHOWN:]))
        print(f'  slowest: {slowest}')
        over = collections.Counter(service for elapsed, service, _ in answers
                                   if elapsed > STORM_P99_TARGET)
        print(f'  above {STORM_P99_TARGET:g} s: {sum(over.values())} calls ('
              + ', '.join(f'{service} {over[service]}'
                          for service in ('get_model_list', 'get_model_state')) + ')')
    for robot in storm['robots']:
        print(f'  {robot}: {storm["received"][robot, "images"]:.1f} images/s, '
              f'{storm["received"][robot, "scans"]:.1f} scans/s received')
    still = storm['still']
    print(f'  simulation time {storm["simulated"]:.2f} s in {storm["seconds"]:.1f} s of wall '
          f'time: real-time factor {storm["simulated"] / storm["seconds"]:.3f}; /clock stood '
          f'still at most {still:.2f} s '
          f'({"kept moving" if still <= CLOCK_STILL_LIMIT else "STOPPED"})')


def print_summary(tally, figures, problems, arguments):
    """Print the table of calls and failures, then the figures of each phase and the verdict."""
    print()
    print(f'{"phase":<16}{"calls":>8}{"ok":>8}{"refused as asked":>18}{"failures":>10}')
    for phase in ('same name', 'mixed', 'killed clients', 'cycles', 'storm'):
        if phase not in tally.calls:
            continue
        outcomes = tally.outcomes.get(phase, {})
        failures = sum(number for kind, number in outcomes.items()
                       if kind not in ('ok', 'refused as asked'))
        print(f'{phase:<16}{tally.calls[phase]:>8}{outcomes.get("ok", 0):>8}'
              f'{outcomes.get("refused as asked", 0):>18}{failures:>10}')
    print(f'{"total":<16}{sum(tally.calls.values()):>8}')
    for (phase, kind), number in sorted(tally.failures().items()):
        example = tally.examples.get((phase, kind), '')
        detail = f' (e.g. {example})' if example else ''
        print(f'  failure in {phase}: {kind} x{number}{detail}')
    if 'mixed_models' in figures:
        print(f'\nmixed phase: {arguments.clients} clients for {arguments.seconds:g} s, '
              f'{figures["mixed_models"]} client models alive at the end')
    if 'arrived' in figures:
        print(f'killed clients: {figures["killed"]} killed in the middle of a spawn, '
              f'{figures["arrived"]} of those spawns reached the world before the kill')
    memory = figures.get('rss', {})
    if WINDOW in memory and figures['cycles'] in memory and figures['cycles'] > WINDOW:
        after, end = memory[WINDOW] / 2**20, memory[figures['cycles']] / 2**20
        print(f'world memory (RSS): {after:.1f} MiB after {WINDOW} cycles, {end:.1f} MiB after '
              f'{figures["cycles"]} ({100 * (end - after) / after:+.1f} %)')
    if 'first' in figures:
        first, last = figures['first'] * 1e3, figures['last'] * 1e3
        print(f'spawn+delete cycle (median): {first:.1f} ms over the first {WINDOW}, '
              f'{last:.1f} ms over the last {WINDOW} ({100 * (last - first) / first:+.1f} %)')
    if 'storm' in figures:
        print_storm(figures['storm'], arguments.clients)
    for problem in problems:
        print(f'PROBLEM: {problem}')
    print('PASS' if not problems and not tally.failures() else 'FAIL')


def drift_problems(figures):
    """Return the memory and speed drifts beyond what is allowed."""
    problems = []
    memory = figures.get('rss', {})
    if 'first' in figures:
        after, end = memory[WINDOW], memory[figures['cycles']]
        if end > after * (1.0 + ALLOWED_DRIFT):
            problems.append(f'world memory grew from {after / 2**20:.1f} MiB to '
                            f'{end / 2**20:.1f} MiB')
        if figures['last'] > figures['first'] * (1.0 + ALLOWED_DRIFT):
            problems.append(f'the last {WINDOW} cycles took {figures["last"] * 1e3:.1f} ms '
                            f'each, the first {figures["first"] * 1e3:.1f} ms')
    return problems


def phase_list(text):
    """Return the phases named in a comma-separated list, in the order they run."""
    names = {name.strip() for name in text.split(',') if name.strip()}
    unknown = sorted(names - set(PHASES))
    if unknown or not names:
        raise argparse.ArgumentTypeError(f'phases are some of {",".join(PHASES)}: {text!r}')
    return tuple(phase for phase in PHASES if phase in names)


def positive_int(text):
    """Return a whole number of at least 1."""
    if not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f'must be a whole number of at least 1: {text!r}')
    return int(text)


def parse_arguments(argv):
    """Read the command line."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--phases', type=phase_list, default=PHASES,
                        help=f'comma-separated phases to run, of {",".join(PHASES)} '
                             '(default all, in that order)')
    parser.add_argument('--seconds', type=float, default=60.0,
                        help='length of the mixed phase (default 60)')
    parser.add_argument('--cycles', type=int, default=1000,
                        help=f'spawn/delete cycles; drift is judged from {2 * WINDOW} on '
                             '(default 1000)')
    parser.add_argument('--clients', type=int, default=8, help='concurrent clients (default 8)')
    parser.add_argument('--killed', type=int, default=5,
                        help='client processes killed in the middle of a spawn (default 5)')
    parser.add_argument('--storm-seconds', type=float, default=60.0,
                        help='wall time the clients call during the sensor storm (default 60)')
    parser.add_argument('--storm-robots', type=positive_int, default=3,
                        help='robots with the largest sensors in the storm (default 3)')
    parser.add_argument('--storm-p99-limit', type=float, default=STORM_P99_TARGET,
                        help='p99 answer time during the storm above which it fails, in s '
                             f'(default {STORM_P99_TARGET:g}, the target)')
    parser.add_argument('--real-time-factor', type=float, default=0.0,
                        help='of the world node: 0 runs flat out, 1 is real time (default 0)')
    return parser.parse_args(argv)


def main(argv=None):
    """Run every phase against a world process of its own; return the exit status."""
    arguments = parse_arguments(argv)
    domain_id = isolate_ros_graph()
    import rclpy
    log = tempfile.NamedTemporaryFile('w+', prefix='world_stress-', suffix='.log', delete=False)
    world = subprocess.Popen(world_command(arguments.real_time_factor), stdout=log,
                             stderr=subprocess.STDOUT)
    rclpy.init()
    tally, figures, problems, nodes = Tally(), {}, [], []
    try:
        nodes = [WorldClient(f'stress_client_{index}') for index in range(arguments.clients)]
        clients = [Services(node) for node in nodes]
        if clients[0].models() != ['tinybot']:
            raise RuntimeError('the world did not come up with tinybot alone')
        models = {name: read_model(name) for name in ('r2d2', 'tinybot')}
        print(f'world pid {world.pid}, ROS domain {domain_id}, its log {log.name} (kept if '
              'anything fails)', flush=True)
        phases = arguments.phases
        if 'same-name' in phases:
            same_name_phase(clients, tally, models)
            print('same name done', flush=True)
        if 'mixed' in phases:
            mixed_problems, figures['mixed_models'] = mixed_phase(clients, tally, models,
                                                                  arguments.seconds, world)
            problems += mixed_problems
            print('mixed done', flush=True)
        if 'killed' in phases:
            figures['killed'] = arguments.killed
            figures['arrived'] = len(killed_client_phase(clients[0], tally, models, world,
                                                         arguments.killed))
            print('killed clients done', flush=True)
        if 'cycles' in phases:
            figures.update(cycles_phase(clients[0], tally, models, world.pid, arguments.cycles))
            problems += drift_problems(figures)
            print('cycles done', flush=True)
        if 'storm' in phases:
            figures['storm'] = storm_phase(clients, tally, models, arguments, world)
            problems += figures['storm']['problems']
            print('sensor storm done', flush=True)
        if clients[0].models() != ['tinybot']:
            problems.append(f'the world ends with {clients[0].models()}, not tinybot alone')
    except RuntimeError as error:
        problems.append(str(error))
    finally:
        if world.poll() is not None:
            problems.append(f'the world process died with status {world.returncode}')
        for node in nodes:
            node.close()
        world.send_signal(signal.SIGINT)
        try:
            world.wait(timeout=10.0)
        except subprocess.TimeoutExpired:
            world.kill()
            world.wait()
        rclpy.try_shutdown()
    log.seek(0)
    internal = [line.strip() for line in log if 'internal error' in line or 'Traceback' in line]
    if internal:
        problems.append(f'the world logged {len(internal)} internal errors, e.g. {internal[0]}')
    print_summary(tally, figures, problems, arguments)
    passed = not problems and not tally.failures()
    log.close()
    if passed:
        os.unlink(log.name)
    return 0 if passed else 1


if __name__ == '__main__':
    sys.exit(main())
