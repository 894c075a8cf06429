"""A batch of robots spawns with one recompile; a bad one in it changes nothing for the rest."""

import mujoco
import numpy as np
from repository import read_model, TINYBOT
from service_tutorial.sim.model import Model
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.validation import DescriptionError, WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot


def tinybot_orders(count, *, spacing=0.5):
    """Return orders for count tinybots in a row along y."""
    urdf = read_model('tinybot')
    return [SpawnOrder(f'tiny{index}', urdf, position=(0.0, spacing * index, 0.0))
            for index in range(count)]


def test_a_batch_spawns_every_robot_with_one_recompile(monkeypatch):
    world = World()
    spawn_file(world, 'first', TINYBOT, position=(-2.0, 0.0, 0.0))
    world.step(100)
    first_before = world.get_model_state('first')
    recompiles = []
    recompile = mujoco.MjSpec.recompile
    monkeypatch.setattr(mujoco.MjSpec, 'recompile',
                        lambda spec, *args: recompiles.append(1) or recompile(spec, *args))
    outcomes = world.spawn(tinybot_orders(10))
    assert len(recompiles) == 1
    assert all(isinstance(outcome, Model) for outcome in outcomes)
    assert world.model_names() == ['first'] + [f'tiny{index}' for index in range(10)]
    for index in range(10):
        assert np.allclose(world.get_model_state(f'tiny{index}').position,
                           (0.0, 0.5 * index, 0.0))
    first_after = world.get_model_state('first')
    assert np.array_equal(first_before.position, first_after.position)
    # Every robot of the batch drives on its own.
    world.models['tiny3'].drive().command_velocity(0.3, 0.0)
    world.step(500)
    assert world.get_model_state('tiny3').position[0] > 0.1
    assert abs(world.get_model_state('tiny4').position[0]) < 0.01


def test_a_batch_is_logged_in_one_line_naming_each_robot_and_where(caplog):
    world = World()
    caplog.set_level('INFO', logger='service_tutorial.world')
    world.spawn(tinybot_orders(3))
    spawned = [record.getMessage() for record in caplog.records
               if record.getMessage().startswith('spawned')]
    assert spawned == ["spawned 3 models: 'tiny0' at [0.0, 0.0, 0.0], "
                       "'tiny1' at [0.0, 0.5, 0.0], 'tiny2' at [0.0, 1.0, 0.0]"]


def test_a_bad_order_in_the_middle_is_refused_and_the_others_spawn():
    world = World()
    orders = tinybot_orders(3)
    orders.insert(1, SpawnOrder('broken', '<robot name="broken"><link name="a"/>'))
    orders.insert(2, SpawnOrder('tiny0', read_model('tinybot')))  # a name the batch took
    orders.insert(3, SpawnOrder('lost', read_model('tinybot'), position=(0.0, float('nan'), 0)))
    outcomes = world.spawn(orders)
    assert [type(outcome) for outcome in outcomes] == [
        Model, DescriptionError, WorldError, WorldError, Model, Model]
    assert 'does not parse as XML' in str(outcomes[1])
    assert str(outcomes[2]) == "a model named 'tiny0' already exists"
    assert 'position contains NaN' in str(outcomes[3])
    assert world.model_names() == ['tiny0', 'tiny1', 'tiny2']


def test_robots_that_only_fail_together_are_told_apart():
    world = World()
    urdf = read_model('tinybot')
    # Two robots in the same place: each alone is fine, together the second overlaps the first
    # (or both simulate, in which case both stay); a robot that cannot compile fails alone.
    bad_inertia = ('<robot name="b"><link name="a"><inertial><mass value="1"/><inertia ixx="1" '
                   'iyy="1" izz="5" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>')
    outcomes = world.spawn([SpawnOrder('one', urdf), SpawnOrder('bad', bad_inertia),
                            SpawnOrder('two', urdf, position=(1.0, 0.0, 0.0))])
    assert isinstance(outcomes[0], Model) and isinstance(outcomes[2], Model)
    assert isinstance(outcomes[1], DescriptionError)
    assert "model 'bad' does not compile" in str(outcomes[1])
    assert world.model_names() == ['one', 'two']
    world.step(100)
    assert np.isfinite(world.data.qpos).all()


def test_an_order_may_stand_relative_to_an_earlier_one_of_the_same_batch():
    world = World()
    urdf = read_model('tinybot')
    half_turn = (np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4))
    world.spawn([
        SpawnOrder('leader', urdf, position=(1.0, 2.0, 0.0), orientation=half_turn),
        SpawnOrder('follower', urdf, position=(1.0, 0.0, 0.0), reference_frame='leader')])
    assert np.allclose(world.get_model_state('follower').position, (1.0, 3.0, 0.0), atol=1e-9)


def test_a_single_spawn_keeps_its_refusals():
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    try:
        spawn_robot(world, 'tinybot', read_model('tinybot'))
    except WorldError as error:
        assert str(error) == "a model named 'tinybot' already exists"
    else:
        raise AssertionError('a taken name was not refused')
