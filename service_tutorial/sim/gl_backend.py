"""
Which GL backend MuJoCo renders through: EGL when nobody chose one and there is no display.

MuJoCo picks its backend as it is imported, and by default loads GLFW, which needs a display
(and which took 50 ms of the world's start-up to load). This module imports nothing of
MuJoCo, so the core can choose before it does; a process that imported MuJoCo first has it
choose again.
"""

import importlib
import os
import sys


def prefer_headless_gl():
    """Make MuJoCo render through EGL when nobody chose a GL backend and there is no display."""
    if os.environ.get('MUJOCO_GL') or os.environ.get('DISPLAY') or \
            os.environ.get('WAYLAND_DISPLAY'):
        return
    os.environ['MUJOCO_GL'] = 'egl'
    # The module moved in mujoco 4 (it was mujoco.gl_context before).
    for name in ('mujoco.rendering.classic.gl_context', 'mujoco.gl_context'):
        gl_context = sys.modules.get(name)
        if gl_context is not None and hasattr(gl_context, '_MUJOCO_GL'):
            importlib.reload(gl_context)
            return
