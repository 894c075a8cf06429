"""Spawning one robot into a ROS-free World, as tests and benchmarks do: a refusal raises."""

from service_tutorial.sim.robot_files import read_path
from service_tutorial.sim.spawning import SpawnOrder


def spawn_robot(world, name, text, **placement):
    """Spawn one robot from its text (URDF unless model_format says); return its Model."""
    outcome, = world.spawn([SpawnOrder(name, text, **placement)])
    if isinstance(outcome, Exception):
        raise outcome
    return outcome


def spawn_file(world, name, path, **placement):
    """Spawn one robot from a file, read as the world reads one; return its Model."""
    robot = read_path(path)
    placement.setdefault('base_dir', robot.base_dir)
    placement.setdefault('model_format', robot.model_format)
    return spawn_robot(world, name, robot.text, **placement)
