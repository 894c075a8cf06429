"""Offscreen rendering of the world: what the default camera shows, and where it projects."""

import math
import os

import mujoco
import numpy as np
import pytest
from repository import R2D2, ROOT, TINYBOT
from service_tutorial.sim.rendering import SceneCamera
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file
import yaml

R2D2_SPAWN = (-2.0, 1.0, 1.0)
R2D2_BODY = (-2.0, 1.0, 1.45)  # the middle of R2-D2 standing at its spawn pose


def camera_defaults():
    """Read the camera parameters of config/world.yaml, the node's defaults."""
    with open(os.path.join(ROOT, 'config', 'world.yaml')) as config_file:
        (node,) = yaml.safe_load(config_file).values()  # mujoco, or a wildcard such as /**
        parameters = node['ros__parameters']
    return {name: parameters['camera_' + name]
            for name in ('width', 'height', 'position', 'look_at', 'fovy')}


@pytest.fixture(scope='module')
def camera():
    """Make the world node's default camera; one GL context for the whole module."""
    defaults = camera_defaults()
    scene_camera = SceneCamera(defaults['width'], defaults['height'], defaults['position'],
                               defaults['look_at'], defaults['fovy'])
    yield scene_camera
    scene_camera.close()


def lesson_world(with_r2d2):
    """Tinybot at the origin and, if asked, R2-D2 at the lesson's spawn pose."""
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    if with_r2d2:
        turn = (math.cos(-math.pi / 4), 0.0, 0.0, math.sin(-math.pi / 4))
        spawn_file(world, 'r2d2', R2D2,
                   position=R2D2_SPAWN, orientation=turn)
    return world


def window(camera, point, radius):
    """Select the image square of half-size radius around a world point's projection."""
    column, row = camera.project(point)
    assert 0 <= column < camera.width and 0 <= row < camera.height, \
        f'{point} is outside the default view, at pixel ({column:.0f}, {row:.0f})'
    column, row = int(round(column)), int(round(row))
    return (slice(max(0, row - radius), row + radius + 1),
            slice(max(0, column - radius), column + radius + 1))


def changed_fraction(first, second, region):
    """Measure the share of pixels in a region whose colour differs clearly in two images."""
    difference = np.abs(first[region].astype(int) - second[region].astype(int)).max(axis=2)
    return float((difference > 30).mean())


def test_default_view_shows_tinybot_and_r2d2(camera):
    empty = World()
    empty_image = camera.render(empty.model, empty.data)
    world = lesson_world(with_r2d2=True)
    image = camera.render(world.model, world.data)
    assert image.shape == (camera.height, camera.width, 3) and image.dtype == np.uint8
    assert image.std() > 10, 'the rendered frame is blank'
    assert np.unique(image.reshape(-1, 3), axis=0).shape[0] > 100
    # Where the robots stand, the picture differs from the empty world's; far off, it does not.
    r2d2_top = camera.project((-2.0, 1.0, 1.9))
    assert 0 <= r2d2_top[1] < camera.height, 'R2-D2 at its spawn height is cut off the view'
    assert changed_fraction(image, empty_image, window(camera, (0.0, 0.0, 0.06), 8)) > 0.5
    assert changed_fraction(image, empty_image, window(camera, R2D2_BODY, 6)) > 0.5
    assert changed_fraction(image, empty_image, window(camera, (-1.0, -0.5, 0.0), 6)) < 0.05


def test_new_model_gets_a_new_renderer(camera):
    world = lesson_world(with_r2d2=False)
    before = camera.render(world.model, world.data)
    region = window(camera, R2D2_BODY, 6)
    turn = (math.cos(-math.pi / 4), 0.0, 0.0, math.sin(-math.pi / 4))
    spawn_file(world, 'r2d2', R2D2,
               position=R2D2_SPAWN, orientation=turn)
    after = camera.render(world.model, world.data)
    assert changed_fraction(after, before, region) > 0.5
    world.delete_model('r2d2')
    assert changed_fraction(camera.render(world.model, world.data), before, region) < 0.05


@pytest.mark.parametrize('width, height, fovy', [(320, 240, 45.0), (800, 500, 70.0)])
def test_ball_appears_where_the_camera_projects_it(width, height, fovy):
    model = mujoco.MjModel.from_xml_string("""
        <mujoco><worldbody><light pos="0 0 4" dir="0 0 -1"/>
          <body pos="-0.6 0.4 0.5"><geom type="sphere" size="0.06" rgba="1 0 0 1"/></body>
        </worldbody></mujoco>""")
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    # 800x500 is larger than the model's offscreen buffer (640x480 by default).
    scene_camera = SceneCamera(width, height, (1.5, -1.5, 1.5), (0.0, 0.0, 0.3), fovy)
    try:
        image = scene_camera.render(model, data)
    finally:
        scene_camera.close()
    assert image.shape == (height, width, 3)
    rows, columns = np.nonzero((image[:, :, 0] > 100) & (image[:, :, 1] < 60))
    assert len(rows) > 20
    column, row = scene_camera.project((-0.6, 0.4, 0.5))
    assert abs(columns.mean() - column) < 2.0 and abs(rows.mean() - row) < 3.0


def test_camera_geometry_is_a_pinhole():
    scene_camera = SceneCamera(640, 480, (3.0, 0.0, 0.0), (0.0, 0.0, 0.0), 90.0)
    assert scene_camera.focal_length == pytest.approx(240.0)
    assert scene_camera.project((0.0, 0.0, 0.0)) == pytest.approx((319.5, 239.5))
    # Looking along -x: world +y is to the camera's right, world +z is up in the image.
    column, row = scene_camera.project((0.0, 1.0, 1.0))
    assert column == pytest.approx(319.5 + 80.0) and row == pytest.approx(239.5 - 80.0)
    assert scene_camera.project((4.0, 0.0, 0.0)) is None
    with pytest.raises(ValueError, match='straight up or down'):
        SceneCamera(64, 48, (0.0, 0.0, 3.0), (0.0, 0.0, 0.0))
