"""The sensors' cost: tinybot's laser and camera against bare MuJoCo, and a listened laser."""

import os
import statistics
import time

from fleet import FleetWorld, model_path, read_model
from harness import wait_for_count
import mujoco
import numpy as np
from report import median_ms, Table
from service_tutorial.testing.spawns import spawn_robot


def cpu_times_in_turns(first, second, count):
    """
    Return the median CPU times of this thread of a call of first and of second, in s.

    The two are called in turns, one call each, count times: this shared machine's speed
    drifts by half within a second, and calls taken in turns see the same drift.
    """
    clock = time.thread_time_ns
    times = np.zeros((count, 2))
    for index in range(count):
        for column, function in enumerate((first, second)):
            start = clock()
            function()
            times[index, column] = clock() - start
    return tuple(float(median) * 1e-9 for median in np.median(times, axis=0))


def sensor_world(samples=360):
    """Return a World in the yard holding tinybot, its laser given samples beams."""
    from service_tutorial.sim.world import World
    world = World(scenery=model_path('yard'))
    urdf = read_model('tinybot').replace('<samples>360</samples>', f'<samples>{samples}</samples>')
    spawn_robot(world, 'tinybot', urdf, base_dir=os.path.dirname(model_path('tinybot')))
    world.step(250)
    return world


def ray_sensor_times(sensor, world, repeats):
    """
    Return the CPU times in us of one reading of a ray sensor and of one bare mj_multiRay.

    The bare call casts the sensor's own rays from where its site stands, so that the ratio is
    what the sensor adds to MuJoCo's ray casting.
    """
    from service_tutorial.sim.plugins.ray_sensor import RAY_GEOM_GROUPS
    sensor.set_active(True)
    world.step(1)
    model, data, site = world.model, world.data, sensor.site_id
    samples = len(sensor.config.directions)
    origin = data.site_xpos[site].copy()
    directions = (sensor.config.directions @ data.site_xmat[site].reshape(3, 3).T).ravel()
    geom_ids, distances = np.zeros(samples, dtype=np.int32), np.zeros(samples)

    def bare():
        mujoco.mj_multiRay(model, data, origin, directions, RAY_GEOM_GROUPS, 1, -1, geom_ids,
                           distances, None, samples, sensor.config.range_max)
    scan, ray = cpu_times_in_turns(sensor.read, bare, repeats)
    return scan * 1e6, ray * 1e6


def scan_row(samples, config):
    """Time one scan of tinybot's laser, and one bare mj_multiRay of the same rays."""
    from service_tutorial.sim.plugins.ray_sensor import RaySensor
    world = sensor_world(samples)
    laser = world.models['tinybot'].plugin(RaySensor)
    scan, ray = ray_sensor_times(laser, world, config.scan_repeats)
    return [f'{samples}-beam scan, tinybot in the yard (us)', scan, ray, scan / ray, 1.5,
            scan / ray <= 1.5]


def camera_frame_row(config):
    """Time one frame of tinybot's camera (320x240), and one of a bare mujoco.Renderer."""
    from service_tutorial.sim.plugins.camera_sensor import CameraSensor
    from service_tutorial.sim.rendering import prefer_headless_gl
    world = sensor_world()
    camera = world.models['tinybot'].plugin(CameraSensor)
    camera.set_active(True)
    world.step(1)  # the first frame makes the renderer and its GL context
    config_camera = camera.config
    prefer_headless_gl()
    renderer = mujoco.Renderer(world.model, config_camera.height, config_camera.width)
    name = world.models['tinybot'].scoped(config_camera.site_name(CameraSensor.kind))

    def bare():
        renderer.update_scene(world.data, camera=name)
        renderer.render()
    frames, bare_frames = [], []
    try:
        bare()
        for _ in range(config.camera_frames):
            start = time.perf_counter()
            camera.read()
            frames.append(time.perf_counter() - start)
            start = time.perf_counter()
            bare()
            bare_frames.append(time.perf_counter() - start)
    finally:
        renderer.close()
        camera.close()
    frame, bare_frame = median_ms(frames), median_ms(bare_frames)
    return [f'{config_camera.width}x{config_camera.height} robot camera frame (ms)', frame,
            bare_frame, frame / bare_frame, 1.5, frame / bare_frame <= 1.5]


def laser_speed_rows(observer, config):
    """Free-running speed of tinybot with its 5 Hz laser listened to, and without."""
    from sensor_msgs.msg import LaserScan
    rounds = []
    with FleetWorld(observer, 1, 0.0, scenery='yard.urdf') as world:
        world.fleet.drive_for(config.warm_up)
        for _ in range(config.speed_rounds):
            quiet, quiet_per_cpu = world.window(config.speed_window)[:2]
            scans, subscription = observer.counter(LaserScan, f'/{world.names[0]}/scan')
            try:
                wait_for_count(scans, world.process, 'scan')
                listened, listened_per_cpu = world.window(config.speed_window)[:2]
            finally:
                observer.node.destroy_subscription(subscription)
            rounds.append((listened, quiet, listened_per_cpu, quiet_per_cpu))
    listened, quiet, listened_per_cpu, quiet_per_cpu = (
        statistics.median(column) for column in zip(*rounds))
    return [['free-running speed, 360-beam laser at 5 Hz listened to / not (sim s per wall '
             's)', listened, quiet, listened / quiet, 0.8, listened / quiet >= 0.8],
            ['the same per CPU second of the world process (sim s per CPU s)',
             listened_per_cpu, quiet_per_cpu, listened_per_cpu / quiet_per_cpu, 0.8,
             listened_per_cpu / quiet_per_cpu >= 0.8]]


def sensor_table(observer, config):
    """Measure the sensors' cost against bare MuJoCo calls, and against not listening."""
    table = Table('sensors', "Sensors: tinybot's laser and camera against bare MuJoCo", [
        ('figure', ''), ('sensor', '.3f'), ('bare', '.3f'), ('ratio', '.3f'),
        ('limit', '.2f'), ('within', '')])
    table.rows = [scan_row(360, config), scan_row(720, config), camera_frame_row(config),
                  *laser_speed_rows(observer, config)]
    table.note = ('scans: CPU time of RaySensor.read() (cast, own geoms hidden, REP 117 '
                  'ranges, noise) against mj_multiRay of the same rays on the same model, the '
                  f'medians of {config.scan_repeats} of each taken in turns; ratio at most the '
                  f'limit. Camera: median wall time of {config.camera_frames} frames of '
                  'CameraSensor.read() against update_scene() and render() of a bare '
                  'mujoco.Renderer at the same camera; ratio at most the limit. Speed: '
                  'mujoco_world driving tinybot (bot0) in the yard, free-running, with a '
                  'subscriber to bot0/scan here against none, '
                  f'medians of {config.speed_rounds} alternating rounds of '
                  f'{config.speed_window} s; ratio at least the limit. Free-running, a '
                  'listened sensor is held to its rate in wall time too, like every stream; '
                  'per CPU second is the steadier figure on a shared machine.')
    return table
