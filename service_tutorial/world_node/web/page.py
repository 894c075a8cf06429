"""
The world node's web page: a viser server with the world in 3D, its sensors and a panel.

viser serves its browser client from inside its Python package (no internet, no build, no GPU
on the server). WebPage.tick() is the node's hook, called on every tick of the step timer: it
returns at once while no browser is connected, so a page nobody opens costs one comparison a
tick; while someone watches it sends the poses and the status UPDATE_RATE times a second of
wall time. The page shows the world's own Panel (panel.py), or the panel the world node was
handed (MujocoWorld(web_panel=...): the lesson's, from service_tutorial/lesson_world.py), which
adds its buttons to it. Buttons never touch the world: they go through the panel's PageClient,
a ROS client like any other.
"""

import collections
import time

from service_tutorial.world_node.parameters import ParameterError
from service_tutorial.world_node.web.panel import Panel
from service_tutorial.world_node.web.scene_view import SceneView
from service_tutorial.world_node.web.sensor_view import SensorView

UPDATE_RATE = 30.0  # Hz of wall time, while a browser is connected
STATUS_PERIOD = 0.25  # s of wall time between two updates of the status line
# The real-time factor shown is measured over about this much wall time.
FACTOR_WINDOW = 1.0  # s
# The viser that scripts/setup installs; a world asked for its page without it names this.
VISER_REQUIREMENT = 'viser>=1.0'


def import_viser():
    """Return the viser module, or raise ParameterError saying how to install it."""
    try:
        import viser  # only with web:=true: it takes a while to import
    except ImportError as error:
        raise ParameterError(
            f'web:=true needs viser, which does not import here ({error}): install it with '
            f"python3 -m pip install '{VISER_REQUIREMENT}'") from None
    return viser


class WebPage:
    """The page of one world node: its server, its 3D view, its panel and its ROS client."""

    def __init__(self, node, host, port, panel_type=None):
        """
        Serve the page of node's world on host:port (viser takes the next port if taken).

        panel_type: the panel to show, Panel or a subclass of it (a contributed panel).
        """
        viser = import_viser()
        self.node = node
        self.world = node.world
        self.server = viser.ViserServer(host=host, port=port, label='service_tutorial',
                                        verbose=False)
        self.watchers = 0
        self.server.on_client_connect(self._client_connected)
        self.server.on_client_disconnect(self._client_disconnected)
        # A new page looks where the world's camera looks.
        parameters = node.parameters
        self.scene = SceneView(self.server, self.world, parameters['camera_position'],
                               parameters['camera_look_at'], parameters['camera_fovy'])
        panel_type = panel_type or Panel
        self.client = panel_type.client_type(node)
        self.panel = panel_type(self.server.gui, self.client)
        self.client.start()
        self.sensors = SensorView(self.server, self.panel, self.client, node)
        shown_host = '127.0.0.1' if host in ('', '0.0.0.0') else host
        self.address = f'http://{shown_host}:{self.server.get_port()}'
        self._next_update = 0.0
        self._next_status = 0.0
        self._samples = collections.deque()  # (wall time, simulation time)
        self.updates = 0  # how many times the view was brought up to date

    def _client_connected(self, _client):
        self.watchers += 1

    def _client_disconnected(self, _client):
        self.watchers -= 1

    def tick(self):
        """Bring the page up to date if someone watches and its time has come; else nothing."""
        if not self.watchers:
            if self.client.subscriptions:  # the last browser just left
                self.sensors.stop()
            return
        now = time.monotonic()
        if now < self._next_update:
            return
        self._next_update = now + 1.0 / UPDATE_RATE
        self.scene.update()
        self.sensors.update(now)
        self.updates += 1
        if now >= self._next_status:
            self._next_status = now + STATUS_PERIOD
            world = self.world
            self.panel.show_status(world.time, self._real_time_factor(now, world.time),
                                   world.model_names(), world.paused)

    def _real_time_factor(self, wall, sim_time):
        """Return simulated over wall seconds in the last FACTOR_WINDOW, or None so far."""
        samples = self._samples
        if samples and sim_time < samples[-1][1]:
            samples.clear()  # a reset put time back
        samples.append((wall, sim_time))
        while len(samples) > 2 and wall - samples[1][0] >= FACTOR_WINDOW:
            samples.popleft()
        first_wall, first_sim = samples[0]
        if wall - first_wall < 0.5 * FACTOR_WINDOW:
            return None
        return (sim_time - first_sim) / (wall - first_wall)

    def close(self):
        """Stop the page's client and its server."""
        self.client.close()
        self.server.stop()
