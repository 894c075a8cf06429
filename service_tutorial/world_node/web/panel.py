"""
The page's panel: the world's status and its sensors, and the place a contributed panel extends.

The status (simulation time, real-time factor, models) is set by the world's thread, a few times
a second while someone watches; so are the sensors' choices offered and their pictures
(sensor_view.py). The world's own page shows this panel alone. A panel contributed to the page
(the lesson's, handed to the world node by service_tutorial/lesson_world.py) is a subclass: it
adds its controls in add_controls(), between the status and the sensors, and names in
client_type the PageClient subclass through which its buttons call ROS (page_client.py).
"""

import threading

import numpy as np
from service_tutorial.world_node.web.page_client import PageClient

NO_CAMERA = 'none'


class Panel:
    """The page's controls and status, in viser's GUI."""

    client_type = PageClient  # what the page makes for this panel's buttons: client

    def __init__(self, gui, client):
        """Lay out the panel on gui: the status, add_controls(), the sensors."""
        self.client = client
        self._status_lock = threading.Lock()
        self.status = gui.add_markdown('**Simulation time** -')
        self.add_controls(gui)
        with gui.add_folder('Sensors'):
            self.show_lasers = gui.add_checkbox('Show lasers', False)
            self.camera_choice = gui.add_dropdown('Camera', (NO_CAMERA,))
            self.camera_image = gui.add_image(np.zeros((2, 2, 3), dtype=np.uint8),
                                              format='jpeg', visible=False)

    def add_controls(self, gui):
        """Add a contributed panel's own controls to gui; the world's own panel has none."""

    def offer_cameras(self, image_topics):
        """Offer the robots' cameras by image topic; a choice that went falls back to none."""
        chosen = self.camera_choice.value
        self.camera_choice.options = (NO_CAMERA, *image_topics)
        if chosen not in image_topics:
            self.camera_choice.value = NO_CAMERA

    def show_status(self, sim_time, real_time_factor, model_names, paused):
        """Show simulation time, real-time factor and the models (from the world's thread)."""
        factor = '-' if real_time_factor is None else f'{real_time_factor:.2f}'
        text = (f'**Simulation time** {sim_time:.2f} s{" (paused)" if paused else ""}  \n'
                f'**Real-time factor** {factor}  \n'
                f'**Models** {", ".join(model_names) or "none"}')
        with self._status_lock:
            if self.status.content != text:
                self.status.content = text
