"""Offscreen rendering, PNG and GIF files, and the trajectory plot, all without ROS."""

import math
import os
import shutil
import subprocess
from xml.etree import ElementTree

import mujoco
import numpy as np
from PIL import Image, ImageSequence
import pytest
from repository import R2D2, ROOT, TINYBOT
from service_tutorial.pictures.image_files import write_animation, write_png
from service_tutorial.pictures.trajectory_plot import write_trajectory_plot
from service_tutorial.sim.rendering import SceneCamera
from service_tutorial.sim.world import World
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
    world.spawn_urdf_file('tinybot', TINYBOT)
    if with_r2d2:
        turn = (math.cos(-math.pi / 4), 0.0, 0.0, math.sin(-math.pi / 4))
        world.spawn_urdf_file('r2d2', R2D2,
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
    world.spawn_urdf_file('r2d2', R2D2,
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


# --- PNG ------------------------------------------------------------------------------------

def read_png(path):
    """Decode a PNG with Pillow, after checking every chunk's CRC; return (H, W, channels)."""
    with Image.open(path) as png:
        assert png.format == 'PNG'
        png.verify()  # the CRC of every chunk
    with Image.open(path) as png:
        pixels = np.asarray(png)
    return pixels.reshape(pixels.shape[0], pixels.shape[1], -1)


def identify(path):
    """Describe an image file with ImageMagick's identify; None without ImageMagick."""
    if shutil.which('identify') is None:
        return None
    result = subprocess.run(['identify', path], capture_output=True, text=True, check=True)
    return result.stdout


@pytest.mark.parametrize('channels', [1, 3, 4])
def test_png_round_trip(tmp_path, channels):
    rng = np.random.default_rng(7)
    image = rng.integers(0, 256, size=(23, 17, channels), dtype=np.uint8)
    image[5:9] = 200  # a flat band
    path = write_png(str(tmp_path / 'pixels.png'), image)
    assert np.array_equal(read_png(path), image)
    description = identify(path)
    if description is not None:
        assert ' PNG 17x23 ' in description


def test_png_refuses_what_it_cannot_write(tmp_path):
    with pytest.raises(ValueError, match='uint8'):
        write_png(str(tmp_path / 'x.png'), np.zeros((4, 4, 3), dtype=np.float32))
    with pytest.raises(ValueError, match='channels'):
        write_png(str(tmp_path / 'x.png'), np.zeros((4, 4, 5), dtype=np.uint8))


# --- GIF ------------------------------------------------------------------------------------

def read_gif(path):
    """Decode a GIF with Pillow into its composed RGB frames and their delays in 1/100 s."""
    frames, delays = [], []
    with Image.open(path) as gif:
        assert gif.format == 'GIF'
        assert gif.info.get('loop') == 0, 'the animation should loop forever'
        for frame in ImageSequence.Iterator(gif):
            frames.append(np.asarray(frame.convert('RGB')))
            delays.append(frame.info['duration'] // 10)
    return frames, delays


def test_long_noisy_clip_decodes_to_its_frames(tmp_path):
    # Noise compresses badly: the LZW code table fills up and starts afresh many times.
    rng = np.random.default_rng(3)
    colours = np.unique(rng.integers(0, 256, size=(200, 3), dtype=np.uint8), axis=0)
    frames = [colours[rng.integers(0, len(colours), size=(120, 160))] for _ in range(6)]
    path = write_animation(str(tmp_path / 'noise.gif'), frames, fps=25.0)
    decoded, delays = read_gif(path)
    assert len(decoded) == len(frames) and delays == [4] * len(frames)
    assert all(np.array_equal(original, shown) for original, shown in zip(frames, decoded))


def test_animation_keeps_few_colours_exactly(tmp_path):
    colours = np.array([[0, 0, 0], [255, 0, 0], [10, 200, 30], [250, 250, 250], [9, 9, 200]],
                       dtype=np.uint8)
    rng = np.random.default_rng(1)
    frames = [colours[rng.integers(0, len(colours), size=(30, 40))] for _ in range(3)]
    decoded, _ = read_gif(write_animation(str(tmp_path / 'few.gif'), frames, fps=10.0))
    assert all(np.array_equal(original, shown) for original, shown in zip(frames, decoded))
    # Many colours: at most 256 of them are kept, and every pixel stays close to its own.
    gradient = [rng.integers(0, 256, size=(100, 200, 3), dtype=np.uint8)]
    decoded, _ = read_gif(write_animation(str(tmp_path / 'many.gif'), gradient, fps=10.0))
    assert len(np.unique(decoded[0].reshape(-1, 3), axis=0)) <= 256
    assert np.abs(decoded[0].astype(int) - gradient[0].astype(int)).mean() < 20.0


def moving_square_frames(count=12, size=(48, 64)):
    """Make a clip: a gradient background, a square that moves, and one repeated frame."""
    height, width = size
    background = np.zeros((height, width, 3), dtype=np.uint8)
    background[..., 0] = np.linspace(20, 220, width, dtype=np.uint8)
    background[..., 2] = np.linspace(200, 40, height, dtype=np.uint8)[:, np.newaxis]
    frames = []
    for i in range(count):
        frame = background.copy()
        frame[10:20, 3 + 4 * i:13 + 4 * i] = (250, 200, 0)
        frames.append(frame)
    if count > 5:
        frames.insert(5, frames[4].copy())  # shown twice as long, stored once
    return frames


def test_animation_decodes_to_the_frames(tmp_path):
    frames = moving_square_frames()
    path = write_animation(str(tmp_path / 'clip.gif'), frames, fps=8.0)
    decoded, delays = read_gif(path)
    assert len(decoded) == len(frames) - 1
    assert sum(delays) == round(len(frames) * 100 / 8.0)
    assert delays[4] == max(delays)
    distinct = frames[:5] + frames[6:]
    for original, shown in zip(distinct, decoded):
        error = np.abs(original.astype(int) - shown.astype(int))
        assert error.mean() < 3.0 and error.max() < 40
    description = identify(path)
    if description is not None:
        assert description.count('GIF') == len(decoded)


def test_animation_of_rendered_frames(tmp_path, camera):
    world = lesson_world(with_r2d2=True)
    frames = []
    for _ in range(4):
        world.step(50)  # R2-D2 falls
        frames.append(camera.render(world.model, world.data))
    path = write_animation(str(tmp_path / 'fall.gif'), frames, fps=10.0)
    decoded, delays = read_gif(path)
    assert len(decoded) == 4 and delays == [10, 10, 10, 10]
    assert np.abs(decoded[-1].astype(int) - frames[-1].astype(int)).mean() < 4.0


def test_animation_refuses_bad_input(tmp_path):
    with pytest.raises(ValueError, match='at least one frame'):
        write_animation(str(tmp_path / 'a.gif'), [], 10.0)
    with pytest.raises(ValueError, match='fps'):
        write_animation(str(tmp_path / 'a.gif'), moving_square_frames(2), 100.0)
    frames = moving_square_frames(2)
    with pytest.raises(ValueError, match='shape'):
        write_animation(str(tmp_path / 'a.gif'), [frames[0], frames[1][:-1]], 10.0)


# --- trajectory plot ------------------------------------------------------------------------

SVG = '{http://www.w3.org/2000/svg}'


def polyline_points(root, element_id):
    """Return the (x, y) points of the polyline with an id in a parsed SVG."""
    line = root.find(f'.//{SVG}polyline[@id="{element_id}"]')
    assert line is not None, f'no polyline {element_id!r}'
    return [tuple(float(v) for v in point.split(',')) for point in line.get('points').split()]


def test_trajectory_plot_is_svg_with_path_and_heading(tmp_path):
    times = np.linspace(0.0, 4.0, 201)
    yaw = np.where(times < 1.0, 0.0, 0.5 * (times - 1.0))
    x, y = 0.001 * np.sin(times), np.zeros_like(times)
    path = write_trajectory_plot(str(tmp_path / 'trajectory.svg'), times, x, y,
                                 np.arctan2(np.sin(yaw), np.cos(yaw)))
    root = ElementTree.parse(path).getroot()
    assert root.tag == f'{SVG}svg'
    assert len(polyline_points(root, 'trajectory')) == len(times)
    heading = polyline_points(root, 'heading')
    assert len(heading) == len(times)
    # Heading goes up the panel (SVG y down) as the robot turns left.
    assert heading[-1][1] < heading[0][1] and heading[-1][0] > heading[0][0]
    assert len(root.findall(f'.//{SVG}g[@id="heading-arrows"]/{SVG}line')) >= 10


def test_trajectory_plot_of_one_sample_and_bad_input(tmp_path):
    path = write_trajectory_plot(str(tmp_path / 'one.svg'), [2.0], [0.5], [0.5], [1.0])
    assert len(polyline_points(ElementTree.parse(path).getroot(), 'trajectory')) == 1
    with pytest.raises(ValueError, match='equally long'):
        write_trajectory_plot(str(tmp_path / 'bad.svg'), [0.0, 1.0], [0.0], [0.0], [0.0])
