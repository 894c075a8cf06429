"""Service round trips: the world node in this process, called from the observer."""

import time

from fleet import core_fleet, fleet_parameters, read_model
from harness import ExecutorThread, quiet_console
from report import percentiles, Table
from service_tutorial.testing.spawns import spawn_robot


class TrivialService:
    """A node whose std_srvs/Trigger service does nothing: the floor of any round trip."""

    def __init__(self):
        from rclpy.node import Node
        from std_srvs.srv import Trigger
        self.node = Node('benchmark_trivial')
        self.trigger_srv = self.node.create_service(Trigger, '~/trigger', self.trigger_callback)

    @staticmethod
    def trigger_callback(request, response):
        """Answer at once."""
        response.success = True
        return response


def spawn_request(index):
    """Return a request that spawns R2-D2 where the lesson does."""
    from service_tutorial.lesson.r2d2 import spawn_pose
    from srv_interfaces.srv import SpawnModel
    return SpawnModel.Request(model_name='r2d2', model_xml=read_model('r2d2'),
                              initial_pose=spawn_pose(), reference_frame='world')


def lesson_core_pose():
    """Return where the lesson spawns R2-D2, for a ROS-free World: position, (w, x, y, z)."""
    from service_tutorial.lesson.r2d2 import SPAWN_POSITION, SPAWN_YAW
    from service_tutorial.sim.frames import yaw_quaternion
    return SPAWN_POSITION, yaw_quaternion(SPAWN_YAW)


def timed_core_spawn_and_delete(world, urdf, pose):
    """Spawn R2-D2 at pose (lesson_core_pose()) on a ROS-free World, delete it; both times."""
    position, orientation = pose
    start = time.perf_counter()
    spawn_robot(world, 'r2d2', urdf, position=position, orientation=orientation)
    middle = time.perf_counter()
    world.delete_model('r2d2')
    return middle - start, time.perf_counter() - middle


def core_round_trips(models_present, calls, *, with_reset=True):
    """Time spawn, delete and reset_world of R2-D2 done directly on a ROS-free World."""
    world = core_fleet(models_present, driving=False)
    urdf, pose = read_model('r2d2'), lesson_core_pose()
    spawns, deletes, resets = [], [], []
    for _ in range(calls):
        spawn, delete = timed_core_spawn_and_delete(world, urdf, pose)
        spawns.append(spawn)
        deletes.append(delete)
    if with_reset:
        position, orientation = pose
        spawn_robot(world, 'r2d2', urdf, position=position, orientation=orientation)
        for _ in range(calls):
            start = time.perf_counter()
            world.reset_world()
            resets.append(time.perf_counter() - start)
    return {'spawn': spawns, 'delete': deletes, 'reset_world': resets}


def node_round_trips(observer, models_present, calls, *, with_reset=True, core=None):
    """
    Time the world node's services from a client in this process.

    The world node runs in real time (its default) with models_present tinybots, on one
    executor thread together with a trivial Trigger service. It logs at its default level; the
    console lines go to a file (see quiet_console).

    Each round times a spawn, a delete and a Trigger call. With core (a ROS-free World holding
    the same models), it first times the same spawn and delete on core: the figures that are
    compared then see the same load on a shared machine. The node's world is paused while the
    core works, so that its ticks do not take turns with the core on the interpreter.
    """
    from rclpy.parameter import Parameter
    from service_tutorial.world_node.node import MujocoWorld
    from srv_interfaces.srv import DeleteModel, SpawnModel
    from std_srvs.srv import Empty, Trigger

    overrides = [Parameter(name, value=value)
                 for name, value in fleet_parameters(models_present, 1.0).items()]
    world = MujocoWorld(parameter_overrides=overrides)
    trivial = TrivialService()
    executor_thread = ExecutorThread(world, trivial.node)
    urdf, pose = read_model('r2d2'), lesson_core_pose()
    try:
        for srv_type, name in ((SpawnModel, '/mujoco/spawn_urdf_model'),
                               (DeleteModel, '/mujoco/delete_model'),
                               (Empty, '/mujoco/reset_world'),
                               (Empty, '/mujoco/pause_physics'),
                               (Empty, '/mujoco/unpause_physics'),
                               (Trigger, '/benchmark_trivial/trigger')):
            observer.wait_for_service(srv_type, name)
        result = {'spawn': [], 'delete': [], 'core spawn': [], 'core delete': [],
                  'trigger': []}
        for index in range(calls + 3):  # the first three warm up
            samples = {}
            if core is not None:
                observer.call(Empty, '/mujoco/pause_physics', Empty.Request())
                spawn, delete = timed_core_spawn_and_delete(core, urdf, pose)
                samples['core spawn'], samples['core delete'] = [spawn], [delete]
                observer.call(Empty, '/mujoco/unpause_physics', Empty.Request())
            samples['spawn'] = observer.timed_calls(
                SpawnModel, '/mujoco/spawn_urdf_model', spawn_request, 1,
                check=lambda r: r.success)
            samples['delete'] = observer.timed_calls(
                DeleteModel, '/mujoco/delete_model',
                lambda _: DeleteModel.Request(model_name='r2d2'), 1,
                check=lambda r: r.success)
            samples['trigger'] = observer.timed_calls(
                Trigger, '/benchmark_trivial/trigger', lambda _: Trigger.Request(), 1,
                check=lambda r: r.success)
            if index >= 3:
                for key, values in samples.items():
                    result[key] += values
        if with_reset:
            observer.call(SpawnModel, '/mujoco/spawn_urdf_model', spawn_request(0))
            result['reset_world'] = observer.timed_calls(
                Empty, '/mujoco/reset_world', lambda _: Empty.Request(), calls)
        return result
    finally:
        executor_thread.stop()
        world.destroy_node()
        trivial.node.destroy_node()


def round_trip_table(observer, config):
    """Spawn, delete and reset_world through the services against their floors."""
    core = core_round_trips(1, config.calls)
    with quiet_console(config.log_path):
        node = node_round_trips(observer, 1, config.calls)
    trivial_p50 = percentiles(node['trigger'])[0]
    table = Table('round_trips', 'Service round trips, world with 1 tinybot in real time (ms)', [
        ('operation', ''), ('calls', 'd'), ('p50', '.2f'), ('p95', '.2f'), ('p99', '.2f'),
        ('core p50', '.2f'), ('core p99', '.2f'), ('Trigger p50', '.2f'),
        ('limit p50', '.2f'), ('within', '')])
    for operation, service in (('spawn', 'spawn_urdf_model (R2-D2)'),
                               ('delete', 'delete_model (R2-D2)'),
                               ('reset_world', 'reset_world')):
        p50, p95, p99 = percentiles(node[operation])
        core_p50, _, core_p99 = percentiles(core[operation])
        limit = trivial_p50 + 2.0 * core_p50
        table.rows.append([service, len(node[operation]), p50, p95, p99, core_p50, core_p99,
                           trivial_p50, limit, p50 <= limit])
    p50, p95, p99 = percentiles(node['trigger'])
    table.rows.append(['Trigger (trivial)', len(node['trigger']), p50, p95, p99, 0.0, 0.0,
                       trivial_p50, trivial_p50, True])
    table.note = ('limit p50 = Trigger p50 + 2 x core p50; core = the same operation on '
                  'World in-process, no ROS; Trigger = trivial service on the same executor')
    return table
