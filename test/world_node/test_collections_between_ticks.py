"""
Full garbage collections stay out of the world's service calls (collections_between_ticks.py).

So does freeing the MuJoCo model and data a spawn or a delete replaced (World.release_replaced):
a weakref.finalize tells where each is freed.

The process's full collections are watched through gc.callbacks, which tell where each one
starts: inside a service callback of the world, or in its tick. Before every call the test makes
a full collection due (the count of generation 2 past its threshold), as a long run of calls
does sooner or later.
"""

import gc
import sys
import weakref

from repository import read_model
from service_tutorial.world_node import pacing
from service_tutorial.world_node.node import MujocoWorld
from simulation_interfaces.msg import Resource, Result, SpawnEntity as SpawnRequest
from simulation_interfaces.srv import SpawnEntities

pytest_plugins = ['service_tutorial.testing.fixtures']

# CPython's threshold of generation 2: a full collection is due once its count is past it.
FULL_THRESHOLD = 10
# The code of every service callback of the world: heard_by_pacer wraps each in one of these.
SERVICE_CALLS = {const for const in pacing.heard_by_pacer.__code__.co_consts
                 if hasattr(const, 'co_name')}
TICK = MujocoWorld.step_callback.__code__


def where_running():
    """Return 'call' inside a service callback of the world, 'tick' in its tick, else ''."""
    frame = sys._getframe(1)
    while frame is not None:
        if frame.f_code in SERVICE_CALLS:
            return 'call'
        if frame.f_code is TICK:
            return 'tick'
        frame = frame.f_back
    return ''


def make_full_collection_due():
    """Push the count of generation 2 past its threshold, as young collections do over time."""
    for _ in range(FULL_THRESHOLD + 1):
        gc.collect(1)


def test_no_full_collection_falls_into_a_call_and_the_ticks_run_those_due(mujoco_sim):
    assert SERVICE_CALLS and gc.get_freeze_count() > 0  # the world's start-up is frozen
    full_collections = []

    def watch(phase, info):
        if phase == 'start' and info['generation'] == 2:
            full_collections.append(where_running())
    r2d2, tinybot = read_model('r2d2'), read_model('tinybot')
    mujoco_sim.spawn_entity('r2d2', r2d2, (1.0, 0.0, 0.0))  # warm: R2-D2 read once
    mujoco_sim.delete_entity('r2d2')
    gc.callbacks.append(watch)
    try:
        for _ in range(3):
            make_full_collection_due()
            mujoco_sim.spawn_entity('r2d2', r2d2, (1.0, 0.0, 0.0))
            make_full_collection_due()
            mujoco_sim.entity_state('r2d2')
            make_full_collection_due()
            mujoco_sim.delete_entity('r2d2')
            make_full_collection_due()
            requests = [SpawnRequest(name=f'bot{index}',
                                     entity_resource=Resource(resource_string=tinybot))
                        for index in range(5)]
            for index, request in enumerate(requests):
                request.initial_pose.pose.position.x = 2.0 + index
            response = mujoco_sim.call(SpawnEntities, 'spawn_entities',
                                       SpawnEntities.Request(spawn_requests=requests))
            assert response.result.result == Result.RESULT_OK, response.result.error_message
            for request in requests:
                make_full_collection_due()
                mujoco_sim.delete_entity(request.name)
        assert 'call' not in full_collections
        # The collections due were not dropped: the world's ticks ran them.
        make_full_collection_due()
        assert mujoco_sim.wait_for(lambda: 'tick' in full_collections)
    finally:
        gc.callbacks.remove(watch)


def test_the_mujoco_data_a_spawn_or_delete_replaced_is_freed_in_a_tick_not_the_call(mujoco_sim):
    world = mujoco_sim.world_node.world
    freed = []
    r2d2 = read_model('r2d2')
    for count, change in enumerate((
            lambda: mujoco_sim.spawn_entity('r2d2', r2d2, (1.0, 0.0, 0.0)),
            lambda: mujoco_sim.delete_entity('r2d2')), start=1):
        for replaced in (world.model, world.data):
            weakref.finalize(replaced, lambda: freed.append(where_running()))
        del replaced
        change()
        assert mujoco_sim.wait_for(lambda: len(freed) == 2 * count)  # freed, not kept
    assert freed == ['tick'] * 4
