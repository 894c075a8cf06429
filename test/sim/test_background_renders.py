"""Cameras drawn on the rendering thread: the world steps on while a frame is being drawn."""

import logging
import threading
import time

from repository import model_path, TEST_MODELS
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

CAMERA_ROBOT = model_path('sensor_camera', TEST_MODELS)  # 160x120 at 10 Hz
RED_BOX = model_path('props/red_box', TEST_MODELS)


def delivered(world, frames, count, timeout=30.0):
    """Hand on finished frames until count came; return whether they did in time."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        world.background_renders.deliver()
        if len(frames) >= count:
            return True
        time.sleep(0.005)
    return False


def test_the_steps_go_on_while_a_frame_is_drawn_and_it_comes_stamped_with_its_snapshot(caplog):
    world = World(background_rendering=True)
    spawn_file(world, 'camera_post', CAMERA_ROBOT)
    spawn_file(world, 'box', RED_BOX, position=(1.5, 0.0, 0.0))
    camera = world.models['camera_post'].plugin(CameraSensor)
    # The rendering thread draws the first frame only once the test lets it.
    drawing, go_on = threading.Event(), threading.Event()
    draw = camera._view.render_snapshot

    def held_draw(shared_drawing=None):
        drawing.set()
        assert go_on.wait(30.0)
        return draw(shared_drawing)
    camera._view.render_snapshot = held_draw
    frames = []
    camera.listener = lambda sensor: frames.append((sensor.reading_time, sensor.image))
    try:
        camera.set_active(True)
        world.step(1)
        snapshot_time = world.time
        assert drawing.wait(30.0), 'the frame was never drawn'
        with caplog.at_level(logging.WARNING):
            # Half a second: five more frames fall due while the first is still drawn.
            world.step(round(0.5 / world.timestep))
        assert world.time > snapshot_time + 0.49
        world.background_renders.deliver()
        assert frames == [] and world.background_renders.busy(camera)
        behind = [record.getMessage() for record in caplog.records
                  if 'takes longer to render' in record.getMessage()]
        assert behind == ["camera 'front_camera' of model 'camera_post' takes longer to render "
                          'than its period of 0.1 s: frames are skipped until it catches up']
        go_on.set()
        assert delivered(world, frames, 1)
        reading_time, image = frames[0]
        assert reading_time == snapshot_time
        assert image.shape == (120, 160, 3)
        red, green, blue = (int(value) for value in image[60, 80])
        assert red > 2 * green and red > 2 * blue, 'the box ahead is in the middle'
        # Caught up: the next frame that falls due is drawn again.
        world.step(round(0.1 / world.timestep) + 1)
        assert delivered(world, frames, 2)
        assert frames[1][0] > world.time - 0.1 - 1e-9
    finally:
        go_on.set()
        camera.close()
        world.background_renders.close()


def test_a_frame_of_a_camera_nobody_listens_to_any_more_is_dropped():
    world = World(background_rendering=True)
    spawn_file(world, 'camera_post', CAMERA_ROBOT)
    camera = world.models['camera_post'].plugin(CameraSensor)
    frames = []
    camera.listener = frames.append
    try:
        camera.set_active(True)
        world.step(1)
        camera.set_active(False)
        deadline = time.monotonic() + 30.0
        while world.background_renders.busy(camera) and time.monotonic() < deadline:
            world.background_renders.deliver()  # hands on the frame once drawn
            time.sleep(0.005)
        assert not world.background_renders.busy(camera)
        assert frames == [] and camera.image is None
    finally:
        camera.close()
        world.background_renders.close()


def test_cameras_of_two_sizes_share_the_rendering_thread_and_see_each_new_model():
    world = World(background_rendering=True)
    spawn_file(world, 'small_post', CAMERA_ROBOT)
    with open(CAMERA_ROBOT) as robot_file:
        larger = robot_file.read().replace('<width>160</width>', '<width>640</width>') \
            .replace('<height>120</height>', '<height>480</height>')
    spawn_robot(world, 'large_post', larger, position=(0.0, 0.0, 0.0))
    cameras = [world.models[name].plugin(CameraSensor) for name in ('small_post', 'large_post')]
    frames = {camera: [] for camera in cameras}
    for camera in cameras:
        camera.listener = lambda sensor: frames[sensor].append(sensor.image)

    def centre_is_red():
        """Take one frame of each camera; tell, for each, whether its centre is red."""
        for camera in cameras:
            frames[camera].clear()
        world.step(round(0.1 / world.timestep) + 1)
        assert delivered(world, frames[cameras[0]], 1) and delivered(world, frames[cameras[1]], 1)
        reds = []
        for camera in cameras:
            image = frames[camera][-1]
            assert image.shape == (camera.config.height, camera.config.width, 3)
            red, green, blue = (int(value) for value in image[image.shape[0] // 2,
                                                              image.shape[1] // 2])
            reds.append(red > 2 * green and red > 2 * blue)
        return reds

    try:
        for camera in cameras:
            camera.set_active(True)
        assert centre_is_red() == [False, False]
        # Each spawn and delete compiles a new model; both cameras draw it at their own size.
        spawn_file(world, 'box', RED_BOX, position=(1.5, 0.0, 0.0))
        assert centre_is_red() == [True, True]
        world.delete_model('box')
        assert centre_is_red() == [False, False]
    finally:
        for camera in cameras:
            camera.close()
        world.background_renders.close()
