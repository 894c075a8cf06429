"""
Loading worlds through the standard: the parking world and the yard back, a robot at a pose.

Each round loads the parking world (LoadWorld: its MJCF wall and crate, tinybot at its start)
and spawns R2-D2 at its parking spot, then loads the yard back and spawns R2-D2 at the lesson's
spawn point, both poses as GetNamedPoses gives them, then loads the yard's twin in SDF (a
Gazebo world of the Fuel Ground Plane and Sun, the yard's walls as a static model and tinybot,
by model://, sdf_twins.py). Taken in turns with each load: what the ROS-free core takes to
build the same world (a World with that scenery and tinybot spawned in it), the scenery's own
compile time (read, checked and compiled into a bare scene), and a trivial Trigger on the
world's executor.
"""

import os
import shutil
import tempfile
import time

from harness import BenchmarkError, prompt_thread_switches, quiet_console
from report import median_ms, Table
from sdf_twins import sdf_twin, write_model_folder, YARD_WORLD
from service_tutorial.testing.spawns import spawn_robot
from standard_interfaces import StandardWorld, TRIGGERS_ALLOWED

# A load reads the world, tries its models in a trial world, then builds it: at most this many
# times the core's own build of the same world, plus the Trigger round trips.
LOAD_LIMIT = 3.0
WORLDS = {'parking': 'parking_spot', 'yard': 'r2d2_spawn'}  # world -> where R2-D2 goes
SCENERY = {'parking': ('parking.xml', 'worlds'), 'yard': ('yard.urdf', 'models')}
SDF_YARD = 'yard (SDF)'


def model_file(name, folder='models'):
    """Return the path of a file this package installs in models/ (or another folder)."""
    from ament_index_python.packages import get_package_share_directory
    return os.path.join(get_package_share_directory('service_tutorial'), folder, name)


def core_world(scenery_path, tinybot):
    """Return the wall time the core takes to build a World with a scenery and tinybot."""
    from service_tutorial.sim.world import World
    start = time.perf_counter()
    world = World(scenery=scenery_path)
    spawn_robot(world, 'tinybot', tinybot)
    return time.perf_counter() - start


def scenery_compile(scenery_path):
    """Return the wall time of reading, checking and compiling a scenery into a bare scene."""
    from service_tutorial.sim.scene import Scene
    from service_tutorial.sim.scenery import Scenery
    start = time.perf_counter()
    Scene(0.002, (0.0, 0.0, -9.81), Scenery(scenery_path)).spec().compile()
    return time.perf_counter() - start


class SdfYard:
    """The yard's SDF twin: its model folders in a folder of its own on GZ_SIM_RESOURCE_PATH."""

    def __init__(self):
        """Write the yard and tinybot as model folders, and put their folder on the path."""
        self.folder = tempfile.mkdtemp(prefix='sdf_yard_')
        for name, static in (('yard', True), ('tinybot', False)):
            with open(model_file(f'{name}.urdf')) as urdf:
                write_model_folder(self.folder, name, sdf_twin(urdf.read(), static=static))
        self._kept = os.environ.get('GZ_SIM_RESOURCE_PATH')
        os.environ['GZ_SIM_RESOURCE_PATH'] = self.folder

    def core_world(self):
        """Return the wall time the core takes to build the world: read, scenery, tinybot."""
        from service_tutorial.sim.spawning import SpawnOrder
        from service_tutorial.sim.world import World
        start = time.perf_counter()
        world_file, scenery = self._scenery()
        timestep, gravity = world_file.physics
        world = World(timestep=timestep, gravity=gravity, scenery=scenery)
        orders = [SpawnOrder.of(model.name, model.source, position=model.position,
                                orientation=model.orientation) for model in world_file.models]
        if any(isinstance(outcome, Exception) for outcome in world.spawn(orders)):
            raise BenchmarkError('the core did not build the SDF yard')
        return time.perf_counter() - start

    def scenery_compile(self):
        """Return the wall time of reading the world and compiling its scenery alone."""
        from service_tutorial.sim.scene import Scene
        start = time.perf_counter()
        world_file, scenery = self._scenery()
        Scene(*world_file.physics, scenery).spec().compile()
        return time.perf_counter() - start

    @staticmethod
    def _scenery():
        from service_tutorial.sim.scenery import Scenery
        from service_tutorial.sim.world_files import parse_world
        from service_tutorial.world_node.packages import package_share
        world_file = parse_world(YARD_WORLD, SDF_YARD, None, package_share)
        return world_file, Scenery.from_sdf(world_file.sdf_world, SDF_YARD,
                                            package_resolver=package_share)

    def close(self):
        """Take the folder off the path and remove it."""
        if self._kept is None:
            os.environ.pop('GZ_SIM_RESOURCE_PATH', None)
        else:
            os.environ['GZ_SIM_RESOURCE_PATH'] = self._kept
        shutil.rmtree(self.folder, ignore_errors=True)


def sdf_round(world, sdf_yard):
    """Return the times of one load of the SDF yard and of what it is taken in turns with."""
    from simulation_interfaces.srv import LoadWorld
    taken = {'core': sdf_yard.core_world(), 'scenery': sdf_yard.scenery_compile(),
             'trigger': world.trigger()}
    taken['load'] = world.timed(LoadWorld, '/load_world',
                                LoadWorld.Request(resource_string=YARD_WORLD))
    return taken


def load_rounds(world, rounds):
    """Load the parking world, the yard and the SDF yard in turns, each against the core."""
    with open(model_file('tinybot.urdf')) as tinybot_file:
        tinybot = tinybot_file.read()
    samples = {f'{name} {kind}': [] for name in (*WORLDS, SDF_YARD)
               for kind in ('load', 'core', 'scenery', 'spawn', 'trigger')}
    sdf_yard = SdfYard()
    try:
        for index in range(rounds + 1):  # the first warms up
            taken = _urdf_round(world, tinybot)
            taken[SDF_YARD] = sdf_round(world, sdf_yard)
            if index > 0:
                for name, times in taken.items():
                    for kind, value in times.items():
                        samples[f'{name} {kind}'].append(value)
    finally:
        sdf_yard.close()
    return samples


def _urdf_round(world, tinybot):
    """Return the times of loading the parking world and the yard, R2-D2 at a named pose."""
    from geometry_msgs.msg import PoseStamped
    from simulation_interfaces.msg import TagsFilter
    from simulation_interfaces.srv import GetNamedPoses, LoadWorld, SpawnEntity
    times = {}
    for name, pose_name in WORLDS.items():
        path = model_file(*SCENERY[name])
        taken = {'core': core_world(path, tinybot), 'scenery': scenery_compile(path),
                 'trigger': world.trigger()}
        taken['load'] = world.timed(LoadWorld, '/load_world', LoadWorld.Request(
            uri=f'package://service_tutorial/worlds/{name}.world.xml'))
        poses = world.call(GetNamedPoses, '/get_named_poses', GetNamedPoses.Request(
            tags=TagsFilter())).poses
        pose = next((p for p in poses if p.name == pose_name), None)
        if pose is None:
            raise BenchmarkError(f'world {name} names no pose {pose_name}')
        initial = PoseStamped()
        initial.pose = pose.pose
        taken['spawn'] = world.timed(SpawnEntity, '/spawn_entity', SpawnEntity.Request(
            name='r2d2', uri='package://service_tutorial/models/r2d2.urdf',
            initial_pose=initial))
        times[name] = taken
    return times


def worlds_table(observer, config):
    """Return the table of LoadWorld of the parking world, the yard and its SDF twin."""
    with quiet_console(config.log_path):
        world = StandardWorld(observer, {})
        try:
            with prompt_thread_switches():
                samples = load_rounds(world, config.standard_rounds)
        finally:
            world.close()
    table = Table('world_loading', 'LoadWorld, a robot at a named pose each time (ms)', [
        ('figure', ''), ('rounds', 'd'), ('LoadWorld p50', '.2f'), ('core world p50', '.2f'),
        ('scenery compile p50', '.2f'), ('Trigger p50', '.3f'), ('limit', '.2f'),
        ('within', '')])
    spawns = []
    for name in (*WORLDS, SDF_YARD):
        load, core = median_ms(samples[f'{name} load']), median_ms(samples[f'{name} core'])
        trigger = median_ms(samples[f'{name} trigger'])
        limit = LOAD_LIMIT * core + TRIGGERS_ALLOWED * trigger
        table.rows.append([
            f'LoadWorld {name} <= {LOAD_LIMIT:g} x core world + {TRIGGERS_ALLOWED:g} x '
            'Trigger', len(samples[f'{name} load']), load, core,
            median_ms(samples[f'{name} scenery']), trigger, limit, load <= limit])
        if name in WORLDS:
            spawns.append(f'{median_ms(samples[f"{name} spawn"]):.1f} ms at {WORLDS[name]}')
    table.note = (
        'Each round loads the parking world, then the yard, by their package:// uris, from '
        'request to answer; each load removes every entity with its topics, reads the world '
        'file, its scenery (kept while unchanged) and tinybot, tries them in a trial world '
        '(once for the same scenery and spawns), builds the world and spawns tinybot. '
        "core world: the ROS-free core's World built with the same scenery and "
        'tinybot spawned, taken in turns with the load. scenery compile: the scenery alone, '
        'read, checked and compiled into a bare scene. After each load R2-D2 is spawned at the '
        f'named pose GetNamedPoses gives ({", ".join(spawns)}, SpawnEntity p50). '
        f'{SDF_YARD}: the yard as a Gazebo world in SDF (sdf_twins.py), loaded as a '
        'resource_string: its includes by model:// from model folders on GZ_SIM_RESOURCE_PATH, '
        'the two Fuel models built in; its core world reads it, builds its static yard as '
        'scenery and spawns its tinybot; nothing is spawned after it.')
    return table
