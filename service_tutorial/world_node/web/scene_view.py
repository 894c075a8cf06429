"""
The world in the page's 3D view: the ground, and every body's visual shapes at its pose.

SceneView.update() runs on the world node's executor thread, inside the step timer's tick,
and only while a browser watches: it reads the world through sim/visual_shapes.py and hands
viser what changed. After a spawn or a delete (the world's compiled model is a new object) the
bodies are drawn afresh; otherwise only the bodies that moved since the last update are sent,
all in one message, so a fleet at rest costs next to nothing.
"""

import math

import numpy as np
from service_tutorial.sim.visual_shapes import body_poses, visual_bodies

# The ground as the world's camera shows it: a dark grey plane, a grid every metre.
GROUND_SIZE = 50.0  # m, as MuJoCo draws its plane
GROUND_COLOUR = (72, 77, 84)
GRID_COLOUR = (110, 116, 124)
# A body whose pose moved by less than this since it was last sent is not sent again.
POSITION_TOLERANCE = 1e-4  # m
ORIENTATION_TOLERANCE = 1e-4  # of a unit quaternion's components


def _rgb(rgba):
    return tuple(int(round(255 * channel)) for channel in rgba[:3])


class SceneView:
    """Keeps viser's scene of one server equal to the world, when asked to."""

    def __init__(self, server, world, camera_position, camera_look_at, camera_fovy):
        """Draw the ground, a new page's camera where given; bodies come with update()."""
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
        self._shown_model = None  # the compiled MjModel the bodies were drawn from
        self._frames = []  # viser frame handles, one per body drawn
        self._body_ids = np.zeros(0, dtype=int)
        self._sent_positions = np.zeros((0, 3))
        self._sent_orientations = np.zeros((0, 4))
        self.redraws = 0  # how many times the bodies were drawn afresh

    def update(self):
        """Draw the bodies afresh if models came or went, else send the poses that changed."""
        if self.world.model is not self._shown_model:
            self._draw_bodies()
            return
        positions, orientations = body_poses(self.world, self._body_ids)
        moved = np.flatnonzero(
            (np.abs(positions - self._sent_positions) > POSITION_TOLERANCE).any(axis=1)
            | (np.abs(orientations - self._sent_orientations) > ORIENTATION_TOLERANCE)
            .any(axis=1))
        if not len(moved):
            return
        with self.server.atomic():
            for index in moved:
                frame = self._frames[index]
                frame.position = positions[index]
                frame.wxyz = orientations[index]
        self._sent_positions[moved] = positions[moved]
        self._sent_orientations[moved] = orientations[moved]

    def _draw_bodies(self):
        """Remove every body drawn and draw the world's bodies at their current poses."""
        scene = self.server.scene
        bodies = visual_bodies(self.world)
        body_ids = np.array([body.body_id for body in bodies], dtype=int)
        positions, orientations = body_poses(self.world, body_ids)
        with self.server.atomic():
            for frame in self._frames:
                frame.remove()
            self._frames = []
            for index, body in enumerate(bodies):
                # Scene names are paths: a body's shapes hang under its frame.
                path = f'/bodies/{body.body_id}'
                self._frames.append(scene.add_frame(
                    path, show_axes=False, position=positions[index],
                    wxyz=orientations[index]))
                for number, shape in enumerate(body.shapes):
                    scene.add_mesh_simple(
                        f'{path}/shape_{number}', shape.vertices, shape.faces,
                        color=_rgb(shape.rgba),
                        opacity=shape.rgba[3] if shape.rgba[3] < 1.0 else None,
                        position=shape.position, wxyz=shape.wxyz)
        self._shown_model = self.world.model
        self._body_ids = body_ids
        self._sent_positions, self._sent_orientations = positions, orientations
        self.redraws += 1
