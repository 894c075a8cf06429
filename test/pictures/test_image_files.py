"""PNG and GIF files and the trajectory plot the pictures are made of, all without ROS."""

import math
import shutil
import subprocess
from xml.etree import ElementTree

import numpy as np
from PIL import Image, ImageSequence
import pytest
from repository import R2D2, TINYBOT
from service_tutorial.pictures.image_files import write_animation, write_png
from service_tutorial.pictures.trajectory_plot import write_trajectory_plot
from service_tutorial.sim import frames
from service_tutorial.sim.rendering import SceneCamera
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file


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


def test_animation_of_rendered_frames(tmp_path):
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    spawn_file(world, 'r2d2', R2D2, position=(-2.0, 1.0, 1.0),
               orientation=frames.yaw_quaternion(-math.pi / 2))
    camera = SceneCamera(480, 360, (1.0, -1.8, 1.3), (-0.9, 0.4, 0.55), 55.0)  # the lesson's view
    rendered = []
    try:
        for _ in range(4):
            world.step(50)  # R2-D2 falls
            rendered.append(camera.render(world.model, world.data))
    finally:
        camera.close()
    path = write_animation(str(tmp_path / 'fall.gif'), rendered, fps=10.0)
    decoded, delays = read_gif(path)
    assert len(decoded) == 4 and delays == [10, 10, 10, 10]
    assert np.abs(decoded[-1].astype(int) - rendered[-1].astype(int)).mean() < 4.0


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
