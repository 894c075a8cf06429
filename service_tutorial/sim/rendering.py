"""
A camera on the MuJoCo scene that renders RGB images offscreen, with or without a display.

No ROS here: the camera takes a MjModel and MjData and gives back pixels. Without a display it
renders through EGL, which needs no window system (MuJoCo's OSMesa backend is the slow
alternative, and GLFW needs a display).
"""

import copy
import importlib
import math
import os
import sys

import mujoco
import numpy as np

# Clipping distances of the camera, in m: the floor stays visible up to FAR_CLIP.
NEAR_CLIP = 0.02
FAR_CLIP = 100.0


def prefer_headless_gl():
    """Make MuJoCo render through EGL when nobody chose a GL backend and there is no display."""
    if os.environ.get('MUJOCO_GL') or os.environ.get('DISPLAY') or \
            os.environ.get('WAYLAND_DISPLAY'):
        return
    os.environ['MUJOCO_GL'] = 'egl'
    # mujoco picks its GL backend when it is imported, which has happened by now; let it pick
    # again. The module moved in mujoco 4 (it was mujoco.gl_context before).
    for name in ('mujoco.rendering.classic.gl_context', 'mujoco.gl_context'):
        gl_context = sys.modules.get(name)
        if gl_context is not None and hasattr(gl_context, '_MUJOCO_GL'):
            importlib.reload(gl_context)
            return


def release_gl_context(renderer):
    """Leave the renderer's GL context current in no thread, so any thread can use it next."""
    # A GL context can be current in one thread at a time, and mujoco.Renderer leaves its own
    # current in the thread that made or last used it: a node destroyed from another thread
    # could not free it. EGL (headless) and GLFW (with a display) are the backends used here.
    context = getattr(renderer, '_gl_context', None)
    egl = sys.modules.get('mujoco.egl')
    glfw = sys.modules.get('mujoco.glfw')
    if egl is not None and isinstance(context, egl.GLContext):
        egl.EGL.eglMakeCurrent(egl.EGL_DISPLAY, egl.EGL.EGL_NO_SURFACE, egl.EGL.EGL_NO_SURFACE,
                               egl.EGL.EGL_NO_CONTEXT)
    elif glfw is not None and isinstance(context, glfw.GLContext):
        glfw.glfw.make_context_current(None)


def pinhole_matrix(width, height, fovy):
    """
    Return the 3x3 matrix K of a rendered image, for sensor_msgs/CameraInfo.

    fovy is the vertical field of view in degrees; pixels are square, and the optical axis
    goes through the image's centre, with pixel centres at integer coordinates.
    """
    focal = 0.5 * height / math.tan(math.radians(fovy) / 2.0)
    return np.array([[focal, 0.0, (width - 1) / 2.0], [0.0, focal, (height - 1) / 2.0],
                     [0.0, 0.0, 1.0]])


class OffscreenCamera:
    """
    Renders a model's scene offscreen into RGB images of one size, from any camera.

    The mujoco.Renderer and its GL context are made on first use, and made again for each new
    model (every spawn and delete compiles a new one).
    """

    def __init__(self, width, height):
        if int(width) < 1 or int(height) < 1:
            raise ValueError(f'camera size must be positive, got {width}x{height}')
        self.width = int(width)
        self.height = int(height)
        self._renderer = None
        self._scene_model = None  # the world's model the renderer was made for

    def render_view(self, model, data, camera, fovy, near, far):
        """
        Render the scene from a camera as an (height, width, 3) uint8 RGB image.

        camera is a mujoco.MjvCamera or the id or name of a camera of the model; fovy is the
        vertical field of view in degrees, near and far the clipping distances in metres.
        """
        self.take_snapshot(model, data, camera, fovy, near, far)
        return self.render_snapshot()

    def take_snapshot(self, model, data, camera, fovy, near, far):
        """
        Copy the scene as render_view() would see it; render_snapshot() draws it later.

        The copy is quick and reads the model and data, so it belongs on the thread that steps
        them; drawing it may happen on another thread, before the next snapshot is taken.
        """
        if model is not self._scene_model:
            self._make_renderer(model)
        self._renderer.update_scene(data, camera)
        # MuJoCo takes the field of view and the clipping distances from the model (a free
        # camera's scale with the model's extent, which changes with every spawn); use ours.
        for eye in self._renderer.scene.camera:
            eye.frustum_near, eye.frustum_far = near, far
            half_height = near * math.tan(math.radians(fovy) / 2.0)
            eye.frustum_top, eye.frustum_bottom = half_height, -half_height
            eye.frustum_center = 0.0
            eye.frustum_width = 0.0  # 0: from the image's aspect ratio

    def render_snapshot(self):
        """Draw the last snapshot as an (height, width, 3) uint8 RGB image, on any thread."""
        try:
            return self._renderer.render()
        finally:
            release_gl_context(self._renderer)

    def _make_renderer(self, model):
        """Create the offscreen renderer, and its GL context, for a new model."""
        self.close()
        prefer_headless_gl()
        render_model = model
        visual = model.vis.global_
        if visual.offwidth < self.width or visual.offheight < self.height:
            # The offscreen buffer's size comes from the model; a copy with a bigger one
            # leaves the world's model as it is.
            render_model = copy.copy(model)
            render_model.vis.global_.offwidth = max(visual.offwidth, self.width)
            render_model.vis.global_.offheight = max(visual.offheight, self.height)
        self._renderer = mujoco.Renderer(render_model, self.height, self.width)
        release_gl_context(self._renderer)
        self._scene_model = model

    def close(self):
        """Release the renderer and its GL context; the next render makes new ones."""
        if self._renderer is not None:
            self._renderer.close()
        self._renderer = None
        self._scene_model = None


class SceneCamera(OffscreenCamera):
    """A pinhole camera at a position, looking at a point, with z up and no roll."""

    def __init__(self, width, height, position, look_at, fovy=45.0):
        super().__init__(width, height)
        if not 0.0 < fovy < 180.0:
            raise ValueError(f'fovy must be between 0 and 180 degrees, got {fovy}')
        self.fovy = float(fovy)
        self.position = np.array(position, dtype=float).reshape(3)
        self.look_at = np.array(look_at, dtype=float).reshape(3)
        offset = self.look_at - self.position
        distance = float(np.linalg.norm(offset))
        if distance < 1e-9:
            raise ValueError(f'camera position {tuple(position)} is its look_at point')
        self.forward = offset / distance
        if abs(self.forward[2]) > 1.0 - 1e-9:
            raise ValueError(f'a camera at {tuple(position)} looking at {tuple(look_at)} looks '
                             'straight up or down: its image has no up direction')
        self.right = np.cross(self.forward, (0.0, 0.0, 1.0))
        self.right /= np.linalg.norm(self.right)
        self.up = np.cross(self.right, self.forward)

        # MuJoCo's free camera: it sits `distance` behind lookat along the azimuth/elevation.
        self.mjv_camera = mujoco.MjvCamera()
        self.mjv_camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.mjv_camera.lookat[:] = self.look_at
        self.mjv_camera.distance = distance
        self.mjv_camera.azimuth = math.degrees(math.atan2(self.forward[1], self.forward[0]))
        self.mjv_camera.elevation = math.degrees(math.asin(self.forward[2]))

    # --- geometry -----------------------------------------------------------------------------

    @property
    def focal_length(self):
        """Focal length in pixels, the same along both axes (square pixels)."""
        return 0.5 * self.height / math.tan(math.radians(self.fovy) / 2.0)

    @property
    def principal_point(self):
        """Image centre (cx, cy) in pixels, with pixel centres at integer coordinates."""
        return (self.width - 1) / 2.0, (self.height - 1) / 2.0

    def intrinsic_matrix(self):
        """Return the 3x3 pinhole matrix K, as in sensor_msgs/CameraInfo."""
        return pinhole_matrix(self.width, self.height, self.fovy)

    def project(self, point):
        """Pixel (column, row) where a world point appears, or None when it is behind."""
        offset = np.asarray(point, dtype=float) - self.position
        depth = float(offset @ self.forward)
        if depth <= 0.0:
            return None
        cx, cy = self.principal_point
        f = self.focal_length
        return (cx + f * float(offset @ self.right) / depth,
                cy - f * float(offset @ self.up) / depth)

    # --- rendering ----------------------------------------------------------------------------

    def render(self, model, data):
        """Render the scene of a model in a state as an (height, width, 3) uint8 RGB image."""
        return self.render_view(model, data, self.mjv_camera, self.fovy, NEAR_CLIP, FAR_CLIP)
