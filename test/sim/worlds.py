"""Worlds the core tests start from, and what they read off a robot's motion in them."""

import math

import numpy as np
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file


def settled_world(name, path, *, steps=250, **world_options):
    """Return a world with one robot from a file, spawned at the origin and stepped to rest."""
    world = World(**world_options)
    spawn_file(world, name, path)
    world.step(steps)
    return world


def heading(quaternion):
    """Return the yaw of a MuJoCo (w, x, y, z) quaternion, in rad."""
    w, x, y, z = quaternion
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


class Turn:
    """How far a heading, read after every small step, has turned: counted on past +-pi."""

    def __init__(self, orientation):
        self.orientation = orientation
        self.last = heading(orientation())
        self.turned = 0.0

    def update(self):
        """Read the heading again and add the change since the last reading."""
        current = heading(self.orientation())
        self.turned += (current - self.last + math.pi) % (2.0 * math.pi) - math.pi
        self.last = current


def drive_and_stop(world, name, linear_x, angular_z, seconds, *, rest_steps=500,
                   odometry=False):
    """
    Command a twist at 50 Hz for some seconds, then stop and let the robot rest for rest_steps.

    Return (turn, distance) from ground truth: the heading change, unwrapped, and the
    straight-line distance between where the robot started and where it stopped; with
    odometry, also the turn the robot's own odometry saw.
    """
    start = world.get_model_state(name).position
    turns = [Turn(lambda: world.get_model_state(name).orientation)]
    if odometry:
        turns.append(Turn(lambda: world.models[name].drive().odometry().orientation))

    def step_and_track():
        world.step(10)
        for turn in turns:
            turn.update()
    for _ in range(round(seconds / 0.02)):
        world.models[name].drive().command_velocity(linear_x, angular_z)
        step_and_track()
    world.models[name].drive().command_velocity(0.0, 0.0)
    for _ in range(rest_steps // 10):
        step_and_track()
    distance = float(np.linalg.norm(world.get_model_state(name).position[:2] - start[:2]))
    return (turns[0].turned, distance, *(turn.turned for turn in turns[1:]))
