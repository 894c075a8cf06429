"""
The simulation core: a MuJoCo world, the models spawned into it and their plugins.

Nothing here imports ROS; the nodes translate messages to and from it.
"""

from service_tutorial.sim.gl_backend import prefer_headless_gl

# Before any module of the core imports MuJoCo, which picks its GL backend as it is imported.
prefer_headless_gl()
