"""
The lesson's spawn and delete services against MuJoCo's own path on a bare MjSpec.

The world node runs in this process in real time with one tinybot, as in the round trips, on
one executor thread with a trivial Trigger service. Each round pauses it, spawns and deletes
R2-D2 MuJoCo's own way on a bare spec holding one tinybot (spawn_cost.BareWorld), plays it
again, then spawns R2-D2 through /mujoco/spawn_urdf_model, deletes it through
/mujoco/delete_model and calls the Trigger: the figures compared see the same load. A service
may cost its factor times MuJoCo's path plus two bare round trips: 1.5 for a warm spawn (a
text the world has read before) and a delete, 5 for a cold one (a text it has not).
"""

import time

from fleet import fleet_parameters, fleet_position, read_model
from harness import ExecutorThread, quiet_console
from report import median_ms, Table
from round_trips import TrivialService
from spawn_cost import BareWorld, COLD, new_text, WARM

# Limit of each row: the service at most this many times MuJoCo's path, plus two Triggers.
FACTORS = {(COLD, 'spawn'): 5.0, (WARM, 'spawn'): 1.5, (WARM, 'delete'): 1.5}
WARM_UP_ROUNDS = 3


def _timed(function, *args):
    start = time.perf_counter()
    result = function(*args)
    return time.perf_counter() - start, result


def _rounds(observer, bare, kind, calls):
    """Time MuJoCo's spawn and delete, the services' and a Trigger in turns; return samples."""
    from service_tutorial.lesson.r2d2 import SPAWN_POSITION, spawn_pose
    from srv_interfaces.srv import DeleteModel, SpawnModel
    from std_srvs.srv import Empty, Trigger
    urdf = read_model('r2d2')
    samples = {'spawn': [], 'delete': [], 'bare spawn': [], 'bare delete': [], 'trigger': []}
    for index in range(calls + WARM_UP_ROUNDS):
        text = new_text(urdf, f'{kind} {index}') if kind == COLD else urdf
        taken = {}
        observer.call(Empty, '/mujoco/pause_physics', Empty.Request())
        taken['bare spawn'], spawned = _timed(bare.spawn, text, 'r2d2', SPAWN_POSITION)
        taken['bare delete'], _ = _timed(bare.delete, spawned)
        observer.call(Empty, '/mujoco/unpause_physics', Empty.Request())
        request = SpawnModel.Request(model_name='r2d2', model_xml=text,
                                     initial_pose=spawn_pose(), reference_frame='world')
        taken['spawn'], response = _timed(observer.call, SpawnModel,
                                          '/mujoco/spawn_urdf_model', request)
        assert response.success, response.status_message
        taken['delete'], response = _timed(observer.call, DeleteModel, '/mujoco/delete_model',
                                           DeleteModel.Request(model_name='r2d2'))
        assert response.success, response.status_message
        taken['trigger'], _ = _timed(observer.call, Trigger, '/benchmark_trivial/trigger',
                                     Trigger.Request())
        if index >= WARM_UP_ROUNDS:
            for key, value in taken.items():
                samples[key].append(value)
    return samples


def lesson_service_samples(observer, calls):
    """Return the samples of warm and cold rounds against a world node with one tinybot."""
    from rclpy.parameter import Parameter
    from service_tutorial.world_node.node import MujocoWorld
    from srv_interfaces.srv import DeleteModel, SpawnModel
    from std_srvs.srv import Empty, Trigger
    overrides = [Parameter(name, value=value)
                 for name, value in fleet_parameters(1, 1.0).items()]
    world = MujocoWorld(parameter_overrides=overrides)
    trivial = TrivialService()
    executor_thread = ExecutorThread(world, trivial.node)
    try:
        for srv_type, name in ((SpawnModel, '/mujoco/spawn_urdf_model'),
                               (DeleteModel, '/mujoco/delete_model'),
                               (Empty, '/mujoco/pause_physics'),
                               (Empty, '/mujoco/unpause_physics'),
                               (Trigger, '/benchmark_trivial/trigger')):
            observer.wait_for_service(srv_type, name)
        bare = BareWorld(read_model('tinybot'), [fleet_position(0)])
        return {kind: _rounds(observer, bare, kind, calls) for kind in (WARM, COLD)}
    finally:
        executor_thread.stop()
        world.destroy_node()
        trivial.node.destroy_node()


def lesson_services_table(observer, config):
    """R2-D2 spawned and deleted through the lesson's services against MuJoCo's own path."""
    with quiet_console(config.log_path):
        samples = lesson_service_samples(observer, config.lesson_calls)
    table = Table('lesson_services', "The lesson's services against MuJoCo's own path on a "
                  'bare MjSpec, world with 1 tinybot in real time (ms)', [
                      ('figure', ''), ('calls', 'd'), ('service p50', '.2f'),
                      ('MuJoCo p50', '.2f'), ('Trigger p50', '.2f'), ('factor', '.1f'),
                      ('limit', '.2f'), ('within', '')])
    for (kind, operation), factor in FACTORS.items():
        taken = samples[kind]
        service, trigger = median_ms(taken[operation]), median_ms(taken['trigger'])
        bare = median_ms(taken[f'bare {operation}'])
        limit = factor * bare + 2.0 * trigger
        figure = f'{kind} spawn R2-D2' if operation == 'spawn' else 'delete R2-D2'
        table.rows.append([figure, len(taken[operation]), service, bare, trigger, factor,
                           limit, service <= limit])
    table.note = ("limit = factor x MuJoCo p50 + 2 x Trigger p50. MuJoCo: MuJoCo's own path on "
                  'a bare MjSpec holding one tinybot (spawn_cost.py: from_string, a free joint, '
                  'attach_body, recompile; spec.delete, recompile), timed with the world node '
                  'paused. Service: /mujoco/spawn_urdf_model and /mujoco/delete_model of R2-D2 '
                  "at the lesson's pose from a client in this process. warm: the text the "
                  'world has read before; cold: a text it has not. Each round times MuJoCo, '
                  'the spawn, the delete and a Trigger in turns')
    return table
