"""A World in this process, no ROS: spawning R2-D2s, and World.step against mj_step."""

import copy
import math
import time

from fleet import model_path
import mujoco
from report import median_ms, Table
from service_tutorial.testing.spawns import spawn_file


def core_table(config):
    """Measure spawning into and stepping a World in this process, no ROS, against limits."""
    from service_tutorial.sim.world import World
    world = World()
    spawn_file(world, 'tinybot', model_path('tinybot'))
    world.step(250)
    spawns = []
    for index in range(config.core_spawns):
        start = time.perf_counter()
        spawn_file(world, f'r2d2_{index}', model_path('r2d2'),
                   position=(2.0 + index, 0.0, 0.0))
        spawns.append(time.perf_counter() - start)
    model, raw = world.model, copy.copy(world.data)  # bare MuJoCo, from the same state
    world_best = raw_best = math.inf
    for _ in range(config.step_rounds):
        start = time.perf_counter()
        world.step(config.step_count)
        world_best = min(world_best, time.perf_counter() - start)
        start = time.perf_counter()
        mujoco.mj_step(model, raw, config.step_count)
        raw_best = min(raw_best, time.perf_counter() - start)
    spawn_p50, ratio = median_ms(spawns), world_best / raw_best
    table = Table('core', 'World in this process, no ROS: tinybot, then R2-D2s beside it', [
        ('figure', ''), ('measured', '.3f'), ('limit', '.2f'), ('within', '')])
    table.rows = [
        [f'spawn R2-D2 p50 of {len(spawns)} (ms)', spawn_p50, 50.0, spawn_p50 < 50.0],
        [f'World.step / bare mj_step time, best of {config.step_rounds} x '
         f'{config.step_count} steps', ratio, 1.5, ratio < 1.5]]
    table.note = ('the world grows by one R2-D2 a spawn; World.step and mj_step step the same '
                  'model from the same state (they stay bit for bit equal, see test_world.py)')
    return table
