"""
Pictures of tinybot's sensors in the yard: its scan seen from above, and its camera's view.

No ROS here: a World with the default scenery (models/yard.urdf), tinybot at its start and
R2-D2 where the lesson drops it; the laser and the camera measure exactly as they do for their
topics. `sensor_pictures --output docs` writes the two PNG files of docs/sensors.md; set
MUJOCO_GL=egl to render without a display.
"""

import argparse
import math
import os
import sys

from ament_index_python.packages import get_package_share_directory
import numpy as np
from PIL import Image, ImageDraw
from service_tutorial.lesson.r2d2 import R2D2_FILE, R2D2_NAME, SPAWN_POSITION, SPAWN_YAW
from service_tutorial.pictures.image_files import write_png
from service_tutorial.sim.frames import yaw_quaternion
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.plugins.ray_sensor import RaySensor
from service_tutorial.sim.rendering import SceneCamera
from service_tutorial.sim.robot_files import read_path
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.world import World

TOP_VIEW_FILE = 'sensors_scan_from_above.png'
CAMERA_FILE = 'sensors_tinybot_camera.png'
# Straight above the yard (a hair to the south, so that north is up in the picture).
TOP_VIEW_POSITION = (0.0, -0.01, 13.0)
TOP_VIEW_FOVY = 47.0  # degrees: the 10 m yard and its walls, with a margin
SETTLE_TIME = 2.0  # s of simulation for R2-D2 to land
SCAN_COLOUR = (255, 40, 40)
BEAM_COLOUR = (255, 140, 140)
BEAM_EVERY = 30  # beams drawn as lines, one in so many; more would hide the robot
BEAM_GAP = 0.3  # m around the laser where no beam is drawn


def model_file(name):
    """Return the installed file of one of the package's models."""
    return os.path.join(get_package_share_directory('service_tutorial'), 'models', name)


def scan_points(world, laser):
    """Return the world points of the latest scan's returns, and where the beams start."""
    data, config = world.data, laser.config
    origin = data.site_xpos[laser.site_id].copy()
    rotation = data.site_xmat[laser.site_id].reshape(3, 3)
    angles = config.angle_min + config.angle_increment * np.arange(config.samples)
    ranges = laser.ranges.astype(float)
    hits = np.isfinite(ranges)
    local = np.stack([ranges * np.cos(angles), ranges * np.sin(angles),
                      np.zeros(config.samples)], axis=1)[hits]
    return origin + local @ rotation.T, origin


def draw_scan(image, camera, points, origin):
    """Draw each return of a scan as a dot, and every BEAM_EVERY-th beam as a line to it."""
    picture = Image.fromarray(image)
    draw = ImageDraw.Draw(picture)
    for index, point in enumerate(points):
        pixel = camera.project(point)
        if pixel is None:
            continue
        offset = point - origin
        distance = float(np.linalg.norm(offset))
        if index % BEAM_EVERY == 0 and distance > BEAM_GAP:
            # Lines start a little away from the laser, so that the robot stays in sight.
            start = camera.project(origin + offset * (BEAM_GAP / distance))
            draw.line([start, pixel], fill=BEAM_COLOUR, width=1)
        x, y = pixel
        draw.ellipse([x - 2, y - 2, x + 2, y + 2], fill=SCAN_COLOUR)
    return np.asarray(picture)


def make_pictures(output, *, yaw=-0.35, size=640):
    """Write the view from above with the scan, and the camera frame; return their paths."""
    world = World(scenery=model_file('yard.urdf'))
    world.spawn([
        SpawnOrder.of('tinybot', read_path(model_file('tinybot.urdf')),
                      orientation=(math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2))),
        SpawnOrder.of(R2D2_NAME, read_path(model_file(R2D2_FILE)), position=SPAWN_POSITION,
                      orientation=yaw_quaternion(SPAWN_YAW))])
    world.step(round(SETTLE_TIME / world.timestep))
    tinybot = world.models['tinybot']
    laser, camera = tinybot.plugin(RaySensor), tinybot.plugin(CameraSensor)
    laser.set_active(True)
    camera.set_active(True)
    world.step(1)
    top_view = SceneCamera(size, size, TOP_VIEW_POSITION, (0.0, 0.0, 0.0), TOP_VIEW_FOVY)
    try:
        image = top_view.render(world.model, world.data)
        image = draw_scan(image, top_view, *scan_points(world, laser))
        frame = camera.image
    finally:
        top_view.close()
        camera.close()
    os.makedirs(output, exist_ok=True)
    paths = (os.path.join(output, TOP_VIEW_FILE), os.path.join(output, CAMERA_FILE))
    write_png(paths[0], image)
    write_png(paths[1], frame)
    return paths, int(np.count_nonzero(np.isfinite(laser.ranges)))


def parse_arguments(argv):
    """Read the command line."""
    parser = argparse.ArgumentParser(
        prog='sensor_pictures',
        description="Draw tinybot's laser scan on the yard seen from above, and save a frame "
                    'of its camera (PNG files).')
    parser.add_argument('--output', default='.', metavar='DIR',
                        help='folder for the two PNG files (default: here)')
    parser.add_argument('--yaw', type=float, default=-0.35,
                        help="tinybot's heading in rad (default -0.35: the red crate ahead)")
    parser.add_argument('--size', type=int, default=640,
                        help='width and height of the view from above, in pixels')
    return parser.parse_args(argv)


def main(args=None):
    """Make the pictures and print where they went."""
    options = parse_arguments(sys.argv[1:] if args is None else args)
    paths, returns = make_pictures(options.output, yaw=options.yaw, size=options.size)
    print(f'{paths[0]}: the yard from above, {returns} laser returns drawn')
    print(f"{paths[1]}: what tinybot's camera sees")
    return 0


if __name__ == '__main__':
    sys.exit(main())
