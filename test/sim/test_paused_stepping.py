"""Stepping a paused world on request, and putting time back to zero without moving anything."""

import numpy as np
import pytest
from repository import TINYBOT
from worlds import settled_world


def motion(world, name='tinybot'):
    """Return everything that describes a robot's motion, and the time, as one vector."""
    state = world.get_model_state(name)
    _, positions, velocities = world.joint_state(name)
    return np.concatenate([[world.time], state.position, state.orientation,
                           state.linear_velocity, state.angular_velocity, positions, velocities])


def test_a_paused_world_steps_on_request_exactly_as_a_running_one():
    running, paused = settled_world('tinybot', TINYBOT), settled_world('tinybot', TINYBOT)
    paused.pause()
    for world in (running, paused):
        world.models['tinybot'].drive().command_velocity(0.3, 0.5)
    assert paused.step(400) == 0  # paused: nothing happens
    assert running.step(400) == 400
    assert paused.step(400, even_if_paused=True) == 400
    assert paused.paused
    np.testing.assert_array_equal(motion(paused), motion(running))
    # The command lapsed (cmd_vel_timeout 0.5 s) in both worlds, at the same step.
    assert running.models['tinybot'].drive().commanded_at is None
    assert paused.models['tinybot'].drive().commanded_at is None


def test_time_goes_back_to_zero_with_every_model_where_it_was():
    world = settled_world('tinybot', TINYBOT)
    drive = world.models['tinybot'].drive()
    drive.command_velocity(0.3, 0.0)
    world.step(200)
    before = world.get_model_state('tinybot')
    assert before.linear_velocity[0] > 0.2
    world.reset_time()
    assert world.time == 0.0
    after = world.get_model_state('tinybot')
    np.testing.assert_array_equal(after.position, before.position)
    np.testing.assert_array_equal(after.linear_velocity, before.linear_velocity)
    # The command lay in the old time: dropped, and odometry starts where the robot is.
    assert drive.commanded_at is None
    assert not np.any(drive.odometry().position)
    # A command in the new time lapses on time (cmd_vel_timeout 0.5 s).
    world.step(250)
    drive.command_velocity(0.3, 0.0)
    world.step(200)
    assert drive.commanded_at == pytest.approx(0.5)
    world.step(60)
    assert drive.commanded_at is None
