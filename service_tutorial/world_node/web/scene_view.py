"""
The world in the page's 3D view: the ground, and every visual shape at its pose.

SceneView.update() runs on the world node's executor thread, inside the step timer's tick,
and only while a browser watches: it reads the world through sim/visual_shapes.py and hands
viser what changed. Equal shapes (the same triangles and colour: the same part of each robot
of a fleet) are drawn as instances of one batched mesh, so an update sends one message of
poses per kind of shape that moved, however many robots there are. After a spawn or a delete
(the world's compiled model is then a new object) the shapes are drawn afresh.
"""

import math

import numpy as np
from service_tutorial.sim.visual_shapes import shape_poses, visual_shapes

# The ground as the world's camera shows it: a dark grey plane, a grid every metre.
GROUND_SIZE = 50.0  # m, as MuJoCo draws its plane
GROUND_COLOUR = (72, 77, 84)
GRID_COLOUR = (110, 116, 124)
# A shape whose pose moved by less than this since it was last sent is not sent again.
POSITION_TOLERANCE = 1e-4  # m
ORIENTATION_TOLERANCE = 1e-4  # of a unit quaternion's components


def _rgb(rgba):
    return tuple(int(round(255 * channel)) for channel in rgba[:3])


class ShapeBatch:
    """The instances of one kind of shape: one viser batched mesh, the geoms it shows."""

    def __init__(self, handle, indices):
        self.handle = handle
        self.indices = indices  # into the scene's arrays of geoms


class SceneView:
    """Keeps viser's scene of one server equal to the world, when asked to."""

    def __init__(self, server, world, camera_position, camera_look_at, camera_fovy):
        """Draw the ground, a new page's camera where given; shapes come with update()."""
        self.server = server
        self.world = world
        server.scene.set_up_direction('+z')
        server.initial_camera.position = tuple(camera_position)
        server.initial_camera.look_at = tuple(camera_look_at)
        server.initial_camera.fov = math.radians(camera_fovy)
        server.scene.add_grid(
            '/ground', width=GROUND_SIZE, height=GROUND_SIZE, plane='xy', cell_size=1.0,
            section_size=5.0, cell_color=GRID_COLOUR, section_color=GRID_COLOUR,
            plane_color=GROUND_COLOUR, plane_opacity=1.0, shadow_opacity=0.0)
        self._shown_model = None  # the compiled MjModel the shapes were drawn from
        self._batches = []
        self._geom_ids = np.zeros(0, dtype=int)
        self._sent_positions = np.zeros((0, 3))
        self._sent_orientations = np.zeros((0, 4))
        self.redraws = 0  # how many times the shapes were drawn afresh

    def update(self):
        """Draw the shapes afresh if models came or went, else send the poses that changed."""
        if self.world.model is not self._shown_model:
            self._draw_shapes()
            return
        positions, orientations = shape_poses(self.world, self._geom_ids)
        moved = ((np.abs(positions - self._sent_positions) > POSITION_TOLERANCE).any(axis=1)
                 | (np.abs(orientations - self._sent_orientations) > ORIENTATION_TOLERANCE)
                 .any(axis=1))
        if not moved.any():
            return
        with self.server.atomic():
            for batch in self._batches:
                if moved[batch.indices].any():
                    batch.handle.batched_positions = positions[batch.indices]
                    batch.handle.batched_wxyzs = orientations[batch.indices]
        self._sent_positions, self._sent_orientations = positions, orientations

    def _draw_shapes(self):
        """Remove every shape drawn and draw the world's shapes at their current poses."""
        shapes = visual_shapes(self.world)
        geom_ids = np.array([shape.geom_id for shape in shapes], dtype=int)
        positions, orientations = shape_poses(self.world, geom_ids)
        kinds = {}  # (triangles, colour) -> indices of the shapes of that kind
        for index, shape in enumerate(shapes):
            key = (shape.vertices.tobytes(), shape.faces.tobytes(), shape.rgba)
            kinds.setdefault(key, []).append(index)
        with self.server.atomic():
            for batch in self._batches:
                batch.handle.remove()
            self._batches = []
            for number, indices in enumerate(kinds.values()):
                shape, indices = shapes[indices[0]], np.array(indices, dtype=int)
                opacity = shape.rgba[3] if shape.rgba[3] < 1.0 else None
                handle = self.server.scene.add_batched_meshes_simple(
                    f'/shapes/kind_{number}', shape.vertices, shape.faces,
                    batched_wxyzs=orientations[indices], batched_positions=positions[indices],
                    batched_colors=_rgb(shape.rgba), opacity=opacity, lod='off')
                self._batches.append(ShapeBatch(handle, indices))
        self._shown_model = self.world.model
        self._geom_ids = geom_ids
        self._sent_positions, self._sent_orientations = positions, orientations
        self.redraws += 1
