"""Spawning the same robot again reuses its description; a delete leaves no trace behind."""

import os
import shutil
import weakref

import mujoco
import numpy as np
import pytest
from repository import model_path, R2D2, read_file, TEST_MODELS, TINYBOT
from service_tutorial.sim.description_cache import DescriptionCache
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.validation import DescriptionError, WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

MESHBOT = model_path('meshbot', TEST_MODELS)
MISSINGBOT = model_path('missingbot', TEST_MODELS)
# What a compiled model holds, by count: a trace of a deleted robot would show in one.
SIZES = ('nbody', 'njnt', 'ngeom', 'nsite', 'ncam', 'nmesh', 'nmeshvert', 'nmat', 'ntex', 'nu',
         'na', 'nsensor', 'nexclude', 'nq', 'nv', 'nnames')


def contents(world):
    """Return the sizes and element names of a world's compiled model."""
    model = world.model
    return {size: getattr(model, size) for size in SIZES}, bytes(model.names)


def test_the_mujoco_model_and_data_a_recompile_replaced_live_until_released():
    world = World()
    for change in (lambda: spawn_file(world, 'tinybot', TINYBOT),
                   lambda: world.delete_model('tinybot')):
        replaced = weakref.ref(world.model), weakref.ref(world.data)
        change()
        assert world.model is not replaced[0]() and world.data is not replaced[1]()
        assert all(ref() is not None for ref in replaced)
        world.release_replaced()
        assert all(ref() is None for ref in replaced)  # nothing else holds them
    world.release_replaced()  # nothing left to release


@pytest.mark.parametrize('path', [TINYBOT, R2D2, MESHBOT])
def test_a_deleted_robot_leaves_nothing_behind(path):
    world, fresh = World(), World()
    for one in (world, fresh):
        spawn_file(one, 'first', TINYBOT)
    for _ in range(3):
        spawn_file(world, 'visitor', path, position=(3.0, 0.0, 0.5))
        spawn_file(world, 'last', TINYBOT, position=(0.0, 3.0, 0.0))
        world.delete_model('visitor')
        world.delete_model('last')
        assert contents(world) == contents(fresh)
        assert world._spec.find_default('visitor::main') is None
    # The names are free again, and a robot spawned after the deletes is whole.
    spawn_file(world, 'visitor', path, position=(3.0, 0.0, 0.5))
    world.step(10)
    assert world.model_names() == ['first', 'visitor']


def test_a_deleted_batch_leaves_nothing_behind_and_every_other_robot_its_state():
    # A batch goes into the world's spec in groups (attachment.GROUP_SIZE): robots leave a
    # group in any order, and the last to leave takes the group's frame with it.
    world, fresh = World(), World()
    for one in (world, fresh):
        spawn_file(one, 'first', TINYBOT)
    world.models['first'].drive().command_velocity(0.2, 0.5)
    urdf = read_file(TINYBOT)
    for _ in range(2):
        world.spawn([SpawnOrder(f'tiny{index}', urdf, position=(2.0, index, 0.0))
                     for index in range(7)])
        world.step(50)
        for name in ('tiny3', 'tiny0', 'tiny6', 'tiny1', 'tiny2', 'tiny5', 'tiny4'):
            kept = {other: world.get_model_state(other)
                    for other in world.model_names() if other != name}
            world.delete_model(name)
            for other, state in kept.items():
                after = world.get_model_state(other)
                assert np.array_equal(after.position, state.position), other
                assert np.array_equal(after.linear_velocity, state.linear_velocity), other
            world.step(10)
        assert contents(world) == contents(fresh)
        assert len(world._spec.frames) == len(fresh._spec.frames)


def test_a_robot_spawned_again_reuses_its_description():
    world = World()
    urdf = read_file(TINYBOT)
    spawn_robot(world, 'bot0', urdf, base_dir=os.path.dirname(TINYBOT))
    spawn_robot(world, 'bot1', urdf, base_dir=os.path.dirname(TINYBOT), position=(1.0, 0.0, 0.0))
    first, second = world.models['bot0'], world.models['bot1']
    assert first.description is second.description
    # Each model has plugins of its own, configured from the shared description.
    assert first.drive() is not second.drive()
    world.models['bot0'].drive().command_velocity(0.2, 0.0)
    world.step(200)
    assert world.models['bot0'].drive().odometry().position[0] > 0.02
    assert abs(world.models['bot1'].drive().odometry().position[0]) < 1e-3
    other = urdf.replace('</robot>', '<!-- another --></robot>')
    spawn_robot(world, 'bot2', other, base_dir=os.path.dirname(TINYBOT), position=(2.0, 0.0, 0.0))
    assert world.models['bot2'].description is not first.description


def test_a_description_is_built_again_when_its_mesh_files_change(tmp_path):
    shutil.copytree(TEST_MODELS, tmp_path / 'models')
    path = str(tmp_path / 'models' / 'meshbot.urdf')
    world = World()
    spawn_file(world, 'before', path)
    box = tmp_path / 'models' / 'meshes' / 'box.obj'
    # The same box, twice as large: different bytes, a different size on disk.
    lines = [(' '.join(['v'] + [str(2.0 * float(v)) for v in line.split()[1:]])
              if line.startswith('v ') else line) for line in box.read_text().splitlines()]
    box.write_text('\n'.join(lines) + '\n# twice as large\n')
    spawn_file(world, 'after', path, position=(2.0, 0.0, 0.0))
    before, after = (world.models[name].description for name in ('before', 'after'))
    assert before is not after
    assert after.spec.meshes[-1].uservert[0] == 2.0 * before.spec.meshes[-1].uservert[0]
    box.unlink()
    spawn_file(world, 'gone', path, position=(4.0, 0.0, 0.0))
    assert world.models['gone'].description.missing_meshes == ('meshes/box.obj',)


def test_a_mesh_folder_is_told_by_what_it_is_not_by_the_path_to_it(tmp_path):
    shutil.copytree(TEST_MODELS, tmp_path / 'first')
    shutil.copytree(TEST_MODELS, tmp_path / 'second')
    box = tmp_path / 'second' / 'meshes' / 'box.obj'
    box.write_text(box.read_text() + '# the second folder\n')  # other bytes, another size
    link = tmp_path / 'link'
    link.symlink_to(tmp_path / 'first')
    urdf = read_file(os.path.join(TEST_MODELS, 'meshbot.urdf'))
    world = World()
    spawn_robot(world, 'direct', urdf, base_dir=str(tmp_path / 'first'))
    spawn_robot(world, 'linked', urdf, base_dir=str(link), position=(2.0, 0.0, 0.0))
    assert world.models['linked'].description is world.models['direct'].description
    # The link now leads to the other folder: its meshes are read there.
    link.unlink()
    link.symlink_to(tmp_path / 'second')
    spawn_robot(world, 'moved', urdf, base_dir=str(link), position=(4.0, 0.0, 0.0))
    moved = world.models['moved'].description
    assert moved is not world.models['direct'].description
    assert all(path.startswith(str(tmp_path / 'second')) for path in moved.mesh_files)


def test_missing_meshes_are_looked_for_at_every_spawn(caplog):
    world = World()
    for index in range(2):
        spawn_file(world, f'missing{index}', MISSINGBOT, position=(2.0 * index, 0.0, 0.0))
    first, second = (world.models[f'missing{index}'].description for index in range(2))
    assert first is not second and first.missing_meshes == second.missing_meshes
    assert caplog.text.count("'meshes/not_there.stl' cannot be had") == 2


def test_refusals_are_not_kept():
    world = World()
    for _ in range(2):
        with pytest.raises(WorldError, match='does not parse as XML'):
            spawn_robot(world, 'bad', '<robot name="x"><link name="a"></robot>')
    assert world.model_names() == []


def test_the_cache_keeps_a_bounded_number_of_descriptions():
    cache = DescriptionCache(None, 0.002, size=2)
    urdf = read_file(TINYBOT)
    texts = [urdf.replace('</robot>', f'<!-- {index} --></robot>') for index in range(3)]
    first = [cache.load(text) for text in texts]
    # The oldest was dropped; the two latest are kept, as str and bytes apart.
    assert cache.load(texts[0]) is not first[0]
    assert cache.load(texts[2]) is first[2]
    assert cache.load(texts[2].encode()) is not first[2]
    with pytest.raises(DescriptionError):
        cache.load('<robot/>')
    assert isinstance(first[0].spec, mujoco.MjSpec)


def test_a_batch_of_one_text_looks_it_up_and_checks_its_meshes_once(monkeypatch):
    cache = DescriptionCache(None, 0.002)
    urdf = read_file(MESHBOT)
    folder = os.path.dirname(MESHBOT)
    cache.load(urdf, folder)
    stats = []
    stat = os.stat
    monkeypatch.setattr(os, 'stat', lambda path, *args, **kwargs: (
        stats.append(path), stat(path, *args, **kwargs))[1])
    batch = cache.for_batch()
    loaded = [batch.load(urdf, folder) for _ in range(5)]
    assert all(description is loaded[0] for description in loaded)
    # The folder and meshbot's four mesh files, once each.
    assert len(stats) == len(set(stats)) == 5 and stats[0] == folder, stats
    # A batch's missing meshes are looked for once too, yet every batch looks again.
    missing = cache.for_batch()
    missing_urdf = read_file(MISSINGBOT)
    assert missing.load(missing_urdf, folder) is missing.load(missing_urdf, folder)
    assert cache.for_batch().load(missing_urdf, folder) is not missing.load(missing_urdf, folder)
