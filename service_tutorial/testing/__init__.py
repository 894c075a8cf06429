"""
Testing against the world: a pytest fixture for users' own tests, and ROS graph isolation.

- fixtures.py: the pytest plugin. In a conftest.py or a test module,
  `pytest_plugins = ['service_tutorial.testing.fixtures']` gives tests `mujoco_sim` (the world,
  paused, on a ROS graph of its own) and `mujoco_sim_factory` (worlds with parameters).
- simulated_world.py: SimulatedWorld, what those fixtures hand a test: the standard's calls,
  step(n), time, add_node(). Usable without pytest too.
- spawns.py: one robot spawned into a ROS-free World (sim/world.py), a refusal raised: for
  tests and benchmarks of the core.
- isolation.py: a ROS domain no other run on the machine holds, for the fixture, the test
  suite, scripts/benchmark and scripts/stress.

Nothing is imported here, so that isolation.py comes without pytest or rclpy.
"""
