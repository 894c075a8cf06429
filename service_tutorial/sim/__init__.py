"""
The simulation core: a MuJoCo world, the models spawned into it and their plugins.

Nothing here imports ROS; the nodes translate messages to and from it.
"""
