"""
The pytest plugin for users' own tests against the world.

Load it in a conftest.py or a test module with
`pytest_plugins = ['service_tutorial.testing.fixtures']`. It gives a test:

- `mujoco_sim`: the default world (tinybot in the yard), paused, on a ROS graph of its own, as a
  SimulatedWorld: step(n), time, add_node(), the standard's calls. Give it other parameters by
  indirect parametrization:
  `@pytest.mark.parametrize('mujoco_sim', [{'timestep': 0.001}], indirect=True)`.
- `mujoco_sim_factory`: `mujoco_sim_factory(namespace='/', **parameters)` starts a world with
  the world node's parameters (models, model_poses, scenery, timestep...); call it as often as
  a test needs.

Every world a test started is torn down after it: its nodes (the test's own ones added with
add_node() too) destroyed, its threads ended, its rclpy Context shut down. Each world is on a
ROS domain of its own on the machine, so the workers of pytest-xdist (`pytest -n 2`) never see
each other's worlds. The plugin is not registered as a pytest11 entry point on purpose: it
loads only where a test asks for it.
"""

import pytest
from service_tutorial.testing.simulated_world import SimulatedWorld


@pytest.fixture
def mujoco_sim_factory():
    """Start worlds with the world node's parameters, paused; close them after the test."""
    started = []

    def start(*, namespace='/', **parameters):
        world = SimulatedWorld(namespace=namespace, **parameters)
        started.append(world)
        return world
    yield start
    for world in reversed(started):
        world.close()


@pytest.fixture
def mujoco_sim(request, mujoco_sim_factory):
    """Start the world, paused, with parameters given by indirect parametrization, if any."""
    return mujoco_sim_factory(**getattr(request, 'param', {}))
