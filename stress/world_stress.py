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
  100 by more than 10 %.

It prints a summary table and exits with status 1 if a property fails. Run it with
scripts/stress [--seconds S] [--cycles N] [--clients N] [--real-time-factor F].
"""

import argparse
import collections
import math
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
            client = self.node.create_client(srv_type, '/mujoco/' + service)
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


def print_summary(tally, figures, problems, seconds, clients):
    """Print the table of calls and failures, then the drift figures and the verdict."""
    print()
    print(f'{"phase":<16}{"calls":>8}{"ok":>8}{"refused as asked":>18}{"failures":>10}')
    for phase in ('same name', 'mixed', 'killed clients', 'cycles'):
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
    print(f'\nmixed phase: {clients} clients for {seconds:g} s, '
          f'{figures.get("mixed_models", 0)} client models alive at the end')
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


def parse_arguments(argv):
    """Read the command line."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--seconds', type=float, default=60.0,
                        help='length of the mixed phase (default 60)')
    parser.add_argument('--cycles', type=int, default=1000,
                        help=f'spawn/delete cycles; drift is judged from {2 * WINDOW} on '
                             '(default 1000)')
    parser.add_argument('--clients', type=int, default=8, help='concurrent clients (default 8)')
    parser.add_argument('--killed', type=int, default=5,
                        help='client processes killed in the middle of a spawn (default 5)')
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
        same_name_phase(clients, tally, models)
        print('same name done', flush=True)
        mixed_problems, figures['mixed_models'] = mixed_phase(clients, tally, models,
                                                              arguments.seconds, world)
        problems += mixed_problems
        print('mixed done', flush=True)
        figures['killed'] = arguments.killed
        figures['arrived'] = len(killed_client_phase(clients[0], tally, models, world,
                                                     arguments.killed))
        print('killed clients done', flush=True)
        figures.update(cycles_phase(clients[0], tally, models, world.pid, arguments.cycles))
        problems += drift_problems(figures)
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
    print_summary(tally, figures, problems, arguments.seconds, arguments.clients)
    passed = not problems and not tally.failures()
    log.close()
    if passed:
        os.unlink(log.name)
    return 0 if passed else 1


if __name__ == '__main__':
    sys.exit(main())
