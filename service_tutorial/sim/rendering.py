"""
A camera on the MuJoCo scene that renders RGB images offscreen, with or without a display.

No ROS here: the camera takes a MjModel and MjData and gives back pixels. Without a display it
renders through EGL, which needs no window system (MuJoCo's OSMesa backend is the slow
alternative, and GLFW needs a display).
"""

import copy
import importlib
import math
import sys

import mujoco
import numpy as np
from service_tutorial.sim.gl_backend import prefer_headless_gl

# Clipping distances of the camera, in m: the floor stays visible up to FAR_CLIP.
NEAR_CLIP = 0.02
FAR_CLIP = 100.0


def release_gl_context(context):
    """Leave a GL context current in no thread, so any thread can use it next."""
    # A GL context can be current in one thread at a time, and stays current in the thread
    # that made or last used it: a node destroyed from another thread could not free it.
    # EGL (headless) and GLFW (with a display) are the backends used here.
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


# Robots' cameras and pictures are drawn with a shadow map this many texels a side: MuJoCo's
# default of 4096 takes 60 ms more to make for every new model, for shadows no image here shows.
SHADOW_SIZE = 1024
# Offscreen buffers up to this many pixels are multisampled (antialiased). A larger one takes
# a quarter of a second to make for every new model, holding the GIL, so it is drawn without.
MULTISAMPLED_PIXELS = 1024 * 1024


def gl_context_class():
    """Return the GLContext class of the GL backend MuJoCo picked last (see prefer_headless_gl)."""
    for name in ('mujoco.rendering.classic.gl_context', 'mujoco.gl_context'):
        try:
            return importlib.import_module(name).GLContext
        except (ImportError, AttributeError):
            continue
    raise RuntimeError('this MuJoCo has no GL context to render offscreen with')


def linear_depth(buffer, near, far):
    """
    Return the distances along the optical axis (m) of a depth buffer drawn with near and far.

    MuJoCo's buffer holds OpenGL's window depth of each pixel, 0 at near and 1 at far, where
    nothing was drawn; nothing drawn reads inf.
    """
    distances = (near * far / (far - buffer * (far - near))).astype(np.float32)
    distances[buffer >= 1.0] = np.inf
    return distances


class SceneSnapshot:
    """A model's scene as one camera sees it, copied to be drawn later, maybe on another thread."""

    def __init__(self):
        self.model = None  # the model the scene was copied from
        self.scene = None
        self.near = self.far = None  # the clipping distances it was taken with, in m
        self._option = mujoco.MjvOption()

    def take(self, model, data, camera, fovy, near, far):
        """
        Copy the scene as the camera sees it; quick, and on the thread that steps model and data.

        camera is a mujoco.MjvCamera or the id of a camera of the model; fovy is the vertical
        field of view in degrees, near and far the clipping distances in metres.
        """
        if model is not self.model:
            # Room for every geom and site twice over, and MuJoCo's decorations: a few
            # milliseconds to make, where MuJoCo's default of 10,000 geoms takes 35.
            capacity = 2 * (model.ngeom + model.nsite + model.ntendon + model.nflex) + 100
            self.scene = mujoco.MjvScene(model, maxgeom=capacity)
            self.model = model
        if not isinstance(camera, mujoco.MjvCamera):
            fixed = mujoco.MjvCamera()
            fixed.type = mujoco.mjtCamera.mjCAMERA_FIXED
            fixed.fixedcamid = int(camera)
            camera = fixed
        self.near, self.far = near, far
        mujoco.mjv_updateScene(model, data, self._option, None, camera,
                               mujoco.mjtCatBit.mjCAT_ALL, self.scene)
        # MuJoCo takes the field of view and the clipping distances from the model (a free
        # camera's scale with the model's extent, which changes with every spawn); use ours.
        for eye in self.scene.camera:
            eye.frustum_near, eye.frustum_far = near, far
            half_height = near * math.tan(math.radians(fovy) / 2.0)
            eye.frustum_top, eye.frustum_bottom = half_height, -half_height
            eye.frustum_center = 0.0
            eye.frustum_width = 0.0  # 0: from the image's aspect ratio


class Drawing:
    """
    One GL context that draws scene snapshots of any size, on whichever thread calls it.

    The GL context is made on first use and kept; MuJoCo's rendering context (the model's
    meshes and textures, offscreen buffers as large as the largest image asked for) is made
    again for each new model. Several cameras can share one Drawing, one at a time.
    """

    def __init__(self):
        self._gl_context = None
        self._context = None
        self._model = None  # the world's model the rendering context was made for
        self._buffer = (0, 0)  # its offscreen buffer's width and height

    def draw(self, snapshot, width, height, *, depth=False):
        """
        Draw a SceneSnapshot as an (height, width, 3) uint8 RGB image.

        depth: return (image, depth) instead, depth being each pixel's distance along the
        optical axis, in m, as (height, width) float32: inf where nothing was drawn.
        """
        self.make_gl_context()
        self._gl_context.make_current()
        try:
            if snapshot.model is not self._model or width > self._buffer[0] or \
                    height > self._buffer[1]:
                self._make_context(snapshot.model, width, height)
            rect = mujoco.MjrRect(0, 0, width, height)
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
            # With depth, no sky (nothing there reads inf) and no reflective floor, which is
            # drawn over the mirrored scene without depth.
            for flag in (mujoco.mjtRndFlag.mjRND_SKYBOX, mujoco.mjtRndFlag.mjRND_REFLECTION):
                snapshot.scene.flags[flag] = not depth
            mujoco.mjr_render(rect, snapshot.scene, self._context)
            pixels = np.empty((height, width, 3), dtype=np.uint8)
            buffer = np.empty((height, width), dtype=np.float32) if depth else None
            mujoco.mjr_readPixels(pixels, buffer, rect, self._context)
            image = np.ascontiguousarray(pixels[::-1])  # GL's rows go bottom up
            if not depth:
                return image
            return image, linear_depth(buffer[::-1], snapshot.near, snapshot.far)
        finally:
            release_gl_context(self._gl_context)

    def make_gl_context(self):
        """Make the GL context, if not made yet, and leave it current in no thread."""
        # With a display, GLFW makes a hidden window: make it on the thread that starts the
        # world, as the world's other windows are, before drawing on the rendering thread.
        if self._gl_context is None:
            prefer_headless_gl()
            self._gl_context = gl_context_class()(1, 1)  # draws offscreen, in any size
            release_gl_context(self._gl_context)

    def _make_context(self, model, width, height):
        """Make the rendering context for a new model, or for a larger image."""
        if self._context is not None:
            self._context.free()
            self._context = None
        visual = model.vis.global_
        buffer = (max(self._buffer[0], width, visual.offwidth),
                  max(self._buffer[1], height, visual.offheight))
        # The buffer's size and the shadows' come from the model; a copy with ours leaves the
        # world's model as it is.
        render_model = copy.copy(model)
        render_model.vis.global_.offwidth, render_model.vis.global_.offheight = buffer
        render_model.vis.quality.shadowsize = min(model.vis.quality.shadowsize, SHADOW_SIZE)
        if buffer[0] * buffer[1] > MULTISAMPLED_PIXELS:
            render_model.vis.quality.offsamples = 0
        self._context = mujoco.MjrContext(render_model, mujoco.mjtFontScale.mjFONTSCALE_150)
        self._model, self._buffer = model, buffer

    def close(self):
        """Free the rendering and GL contexts, from any thread; the next draw makes new ones."""
        if self._gl_context is None:
            return
        if self._context is not None:
            self._gl_context.make_current()
            self._context.free()
            release_gl_context(self._gl_context)
        self._gl_context.free()
        self._gl_context = None
        self._context = None
        self._model = None
        self._buffer = (0, 0)


class OffscreenCamera:
    """
    Renders a model's scene offscreen into RGB images of one size, from any camera.

    A snapshot of the scene is taken on the thread that steps the model, and drawn by a
    Drawing: the camera's own, made on first use, or one it is given (shared by the world's
    cameras on its rendering thread).
    """

    def __init__(self, width, height):
        if int(width) < 1 or int(height) < 1:
            raise ValueError(f'camera size must be positive, got {width}x{height}')
        self.width = int(width)
        self.height = int(height)
        self.snapshot = SceneSnapshot()
        self.drawing = None  # the camera's own Drawing, once it drew with it

    def render_view(self, model, data, camera, fovy, near, far):
        """
        Render the scene from a camera as an (height, width, 3) uint8 RGB image.

        camera is a mujoco.MjvCamera or the id of a camera of the model; fovy is the vertical
        field of view in degrees, near and far the clipping distances in metres.
        """
        self.take_snapshot(model, data, camera, fovy, near, far)
        return self.render_snapshot()

    def take_snapshot(self, model, data, camera, fovy, near, far):
        """Copy the scene as render_view() would see it; render_snapshot() draws it later."""
        self.snapshot.take(model, data, camera, fovy, near, far)

    def render_snapshot(self, drawing=None, *, depth=False):
        """
        Draw the last snapshot with a Drawing (the camera's own by default), on any thread.

        depth: return (image, depth) as Drawing.draw does.
        """
        if drawing is None:
            if self.drawing is None:
                self.drawing = Drawing()
            drawing = self.drawing
        return drawing.draw(self.snapshot, self.width, self.height, depth=depth)

    def close(self):
        """Release the camera's own Drawing and its GL context; the next render makes new ones."""
        if self.drawing is not None:
            self.drawing.close()
        self.drawing = None
        self.snapshot = SceneSnapshot()


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
