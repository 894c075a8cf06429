"""A World in this process, no ROS: spawning R2-D2s, World.step against mj_step, bounds."""

import copy
import math
import time

from fleet import model_path
import mujoco
import numpy as np
from report import median_ms, Table
from service_tutorial.testing.spawns import spawn_file

# The hull row: the two answers within this many passes over the points (points @ direction,
# argmin: one support point of GJK, at most 64 of them an answer).
HULL_PASSES_LIMIT = 128.0


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
    table.rows.append(hull_row())
    table.note = ('the world grows by one R2-D2 a spawn; World.step and mj_step step the same '
                  'model from the same state (they stay bit for bit equal, see test_world.py); '
                  'bounds: a box of 1 m against the convex hull of a cloud of a million points '
                  'around it, and of the part of that cloud beside it (GetEntityBounds of a '
                  'mesh that large)')
    return table


def hull_row():
    """Return the row of a box against the hulls of a million points, in passes over them."""
    from service_tutorial.sim.bounds import OrientedBoxes, overlaps_hull
    box = OrientedBoxes(centres=np.zeros((1, 3)), rotations=np.eye(3)[np.newaxis],
                        half_sizes=np.full((1, 3), 0.5))
    points = np.random.default_rng(1).uniform(-4.0, 4.0, (1_000_000, 3))
    around = points[np.abs(points).max(axis=1) > 0.6]  # a cloud around the box, not in it
    beside = around[around[:, 0] > 0.6]
    start = time.perf_counter()
    answers = overlaps_hull(box, around), overlaps_hull(box, beside)
    took = time.perf_counter() - start
    passes = []
    for _ in range(5):
        start = time.perf_counter()
        np.argmin(around @ np.array([0.3, -0.5, 0.8]))
        passes.append(time.perf_counter() - start)
    ratio = took / min(passes)
    right = answers == (True, False)
    return [f'box against the hull of a million points, around it and beside it: {took * 1e3:.1f} '
            'ms, in passes over the points' + ('' if right else f'; wrong answers {answers}'),
            ratio, HULL_PASSES_LIMIT, right and ratio <= HULL_PASSES_LIMIT]
