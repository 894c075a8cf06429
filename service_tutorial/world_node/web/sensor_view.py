"""
The robots' sensors on the page: lasers as points in the 3D view, one camera's image in the panel.

The page listens as any ROS client would: while "Show lasers" is ticked it subscribes to every
laser's scan topic, while a camera is chosen to that camera's image topic, so the sensors
measure exactly as they do for any other subscriber (and do not while nobody listens). What it
shows comes from the sensors' own last readings, read on the world's thread in the page's tick:
a laser's hits in the world as it cast them, a camera's last frame, scaled down to at most
IMAGE_WIDTH pixels across before it goes to the browser. When the last browser leaves, the
page stops listening.
"""

import math

import numpy as np
from sensor_msgs.msg import Image, LaserScan
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.plugins.ray_sensor import RaySensor
from service_tutorial.world_node.faces.sensor import SensorFace

LASER_COLOUR = (255, 0, 0)  # pure red: nothing else in the yard is
LASER_POINT_SIZE = 0.04  # m
IMAGE_WIDTH = 640  # px at most, across the panel
IMAGE_PERIOD = 0.1  # s of wall time between two images sent, at most
LOOK_PERIOD = 0.25  # s of wall time between two looks for the robots' sensors


def sensor_topics(node):
    """Return ((scan topic, RaySensor) ...), ((image topic, CameraSensor) ...) of node's robots."""
    lasers, cameras = [], []
    for interface in node.models.values():
        if not interface.topics_made:
            continue
        for face in interface.faces:
            if not isinstance(face, SensorFace) or not face.watch.publishers:
                continue
            sensor, topic = face.sensor, face.watch.publishers[0].topic_name  # scan or image
            if isinstance(sensor, RaySensor):
                lasers.append((topic, sensor))
            elif isinstance(sensor, CameraSensor):
                cameras.append((topic, sensor))
    return tuple(lasers), tuple(cameras)


def shown_image(sensor):
    """Return a camera's last frame as RGB, scaled down to at most IMAGE_WIDTH across."""
    pixels = sensor.image
    stride = max(1, math.ceil(pixels.shape[1] / IMAGE_WIDTH))
    pixels = pixels[::stride, ::stride]
    encoding = sensor.config.encoding
    if encoding == 'mono8':
        return np.repeat(pixels[:, :, None], 3, axis=2)
    if encoding == 'bgr8':
        return np.ascontiguousarray(pixels[:, :, ::-1])
    return np.ascontiguousarray(pixels)


class SensorView:
    """Keeps the page's laser points and camera image equal to what it asks to see."""

    def __init__(self, server, panel, client, node):
        """Show the sensors of node's robots that panel's controls ask for; listen via client."""
        self.server = server
        self.panel = panel
        self.client = client
        self.node = node
        self._lasers = self._cameras = ()
        self._clouds = {}  # scan topic -> [viser point cloud, reading time shown]
        self._clouds_made = 0  # names each new cloud
        self._image_shown = (None, None)  # (image topic, reading time)
        self._next_image = 0.0
        self._next_look = 0.0
        self.images_sent = 0

    def update(self, wall_time):
        """Listen to what the panel asks for, and show the newest readings (world's thread)."""
        if wall_time >= self._next_look:  # a fleet has hundreds of faces: not every update
            self._next_look = wall_time + LOOK_PERIOD
            lasers, cameras = sensor_topics(self.node)
            if (lasers, cameras) != (self._lasers, self._cameras):
                self._lasers, self._cameras = lasers, cameras
                self.panel.offer_cameras([topic for topic, _ in cameras])
        lasers, cameras = self._lasers, self._cameras
        shown_lasers = lasers if self.panel.show_lasers.value else ()
        chosen = self.panel.camera_choice.value
        camera = next((entry for entry in cameras if entry[0] == chosen), None)
        wanted = {topic: LaserScan for topic, _ in shown_lasers}
        if camera is not None:
            wanted[camera[0]] = Image
        self.client.listen(wanted)
        self._show_lasers(shown_lasers)
        self._show_camera(camera, wall_time)

    def _show_lasers(self, lasers):
        for topic in set(self._clouds) - {topic for topic, _ in lasers}:
            self._clouds.pop(topic)[0].remove()
        for topic, laser in lasers:
            shown = self._clouds.get(topic)
            if laser.reading_time is None or (shown and shown[1] == laser.reading_time):
                continue
            points = laser.hit_points().astype(np.float32)
            if shown is None:
                self._clouds_made += 1
                handle = self.server.scene.add_point_cloud(
                    f'/lasers/{self._clouds_made}', points, LASER_COLOUR,
                    point_size=LASER_POINT_SIZE, point_shape='circle', point_shading='flat')
                self._clouds[topic] = [handle, laser.reading_time]
            else:
                shown[0].points = points
                shown[1] = laser.reading_time

    def _show_camera(self, camera, wall_time):
        image = self.panel.camera_image
        if camera is None:
            image.visible = False
            self._image_shown = (None, None)
            return
        topic, sensor = camera
        if (sensor.image is None or self._image_shown == (topic, sensor.reading_time)
                or wall_time < self._next_image):
            return
        self._next_image = wall_time + IMAGE_PERIOD
        self._image_shown = (topic, sensor.reading_time)
        image.image = shown_image(sensor)
        image.visible = True
        self.images_sent += 1

    def stop(self):
        """Stop listening and take the points away: nobody watches."""
        self.client.listen({})
        for handle, _ in self._clouds.values():
            handle.remove()
        self._clouds = {}
        self._image_shown = (None, None)
