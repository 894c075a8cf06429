"""
gz-sim's sensors in the ROS-free core: what they read of their <sensor>, and what they measure.

The suite's surveyor (an SDF model with a gpu_lidar, a depth camera, an IMU and a NavSat) is
spawned into a World before a wall whose face stands 2 m ahead of its chassis: the lidar's rays
and the depth camera's depth buffer read it, the IMU gravity, the NavSat the world's origin.
Settings are read as gz-sim reads them (topics made valid or given up for gz's default, frames
scoped) and absurd ones are refused naming the tag.
"""

import math
import os

import numpy as np
import pytest
from repository import model_path, read_file, TEST_MODELS
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.geodesy import SphericalCoordinates
from service_tutorial.sim.plugins.gz_camera import GzCamera
from service_tutorial.sim.plugins.gz_imu import GzImu
from service_tutorial.sim.plugins.gz_lidar import GzLidar
from service_tutorial.sim.plugins.gz_navsat import GzNavSat
from service_tutorial.sim.validation import WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

SURVEYOR = os.path.join(TEST_MODELS, 'sdf', 'models', 'surveyor', 'model.sdf')
WALL = model_path('props/wall', TEST_MODELS)
ORIGIN = SphericalCoordinates(latitude_deg=-33.8568, longitude_deg=151.2153, elevation=5.0)


def surveyor_world(**world_settings):
    """Spawn surveyor at the origin and a wall 2 m ahead; let it settle; return both."""
    world = World(timestep=0.001, **world_settings)
    robot = spawn_file(world, 'surveyor', SURVEYOR)
    spawn_file(world, 'wall', WALL, position=(2.0, 0.0, 0.0))
    world.step(300)
    return world, robot


def reading_of(world, sensor):
    """Switch a sensor on, step until it reads, and switch it off; return the sensor."""
    sensor.set_active(True)
    start = sensor.reading_time
    while sensor.reading_time == start:
        world.step(1)
    sensor.set_active(False)
    return sensor


def test_the_sensors_measure_the_wall_gravity_and_the_origin():
    world, robot = surveyor_world(spherical_coordinates=ORIGIN)
    chassis = world.get_model_state('surveyor').position
    lidar = reading_of(world, robot.plugin(GzLidar))
    assert lidar.middle_row()[90] == pytest.approx(2.0 - (chassis[0] + 0.1), abs=0.02)
    camera = reading_of(world, robot.plugin(GzCamera))
    assert camera.image is None and camera.depth.dtype == np.float32
    assert float(camera.depth[24, 32]) == pytest.approx(2.0 - (chassis[0] + 0.15), abs=0.02)
    imu = reading_of(world, robot.plugin(GzImu))
    assert imu.linear_acceleration[2] == pytest.approx(9.81, abs=0.05)
    assert imu.orientation == pytest.approx([1.0, 0.0, 0.0, 0.0], abs=1e-3)
    navsat = reading_of(world, robot.plugin(GzNavSat))
    assert (navsat.latitude, navsat.longitude) == pytest.approx((-33.8568, 151.2153), abs=1e-7)
    assert navsat.altitude == pytest.approx(5.0 + chassis[2] + 0.05, abs=0.005)


def test_an_imus_orientation_is_from_its_pose_at_spawn_as_gz_has_it():
    world = World(timestep=0.001)
    robot = spawn_file(world, 'surveyor', SURVEYOR, orientation=(math.cos(0.5), 0.0, 0.0,
                                                                 math.sin(0.5)))
    world.step(300)
    imu = reading_of(world, robot.plugin(GzImu))
    assert abs(imu.orientation[0]) == pytest.approx(1.0, abs=1e-3)  # turned 1 rad at spawn


def test_a_navsat_in_a_world_with_no_place_on_the_earth_reads_zeros():
    world, robot = surveyor_world()
    navsat = reading_of(world, robot.plugin(GzNavSat))
    assert (navsat.latitude, navsat.longitude, navsat.altitude) == (0.0, 0.0, 0.0)


def test_topics_and_frames_take_gz_names_or_the_blocks():
    world, robot = surveyor_world(name='plaza')
    lidar, camera, navsat = (robot.plugin(kind) for kind in (GzLidar, GzCamera, GzNavSat))
    below = '/world/plaza/model/surveyor/link/chassis/sensor/'
    assert lidar.gz_topics('surveyor', 'plaza') == {'scan': below + 'front_lidar/scan',
                                                    'points': None}
    assert camera.gz_topics('surveyor', 'plaza') == {
        'image': None, 'depth_image': below + 'depth/depth_image',
        'points': below + 'depth/depth_image/points', 'camera_info': below + 'depth/camera_info'}
    assert lidar.gz_frame('surveyor') == 'surveyor/chassis/front_lidar'
    assert navsat.gz_frame('surveyor') == 'gps_link'


def with_lidar(old, new):
    text = read_file(SURVEYOR)
    assert old in text
    return text.replace(old, new)


def test_a_topic_gz_cannot_take_gives_way_to_the_default_and_is_named():
    world = World(timestep=0.001)
    robot = spawn_robot(world, 'surveyor', with_lidar(
        '<update_rate>10</update_rate>', '<update_rate>10</update_rate><topic>@</topic>'),
        model_format='sdf')
    assert robot.plugin(GzLidar).gz_topics('surveyor', 'default')['scan'] == \
        '/world/default/model/surveyor/link/chassis/sensor/front_lidar/scan'
    assert any("<topic> '@' is no valid gz topic" in note
               for note in robot.description.notes)


@pytest.mark.parametrize('old, new, words', [
    ('<always_on>true</always_on>', '<always_on>maybe</always_on>', '<always_on> must be'),
    ('<min_angle>-1.5707963267948966</min_angle>', '<min_angle>2</min_angle>',
     'is above its <max_angle>'),
    ('<range><min>0.1</min><max>8</max></range>', '<range><min>0.1</min></range>',
     'has no <lidar/range/max>'),
    ('<samples>181</samples>', '<samples>181</samples></horizontal><vertical>'
     '<samples>200</samples></vertical><horizontal>', '181 x 200 = 36200 beams'),
    ('<gz_frame_id>gps_link</gz_frame_id>', '<gz_frame_id>gps link</gz_frame_id>',
     '<gz_frame_id>'),
])
def test_absurd_sensor_settings_are_refused_naming_the_tag(old, new, words):
    world = World(timestep=0.001)
    with pytest.raises((UrdfError, WorldError), match=words.replace('<', '.').replace(
            '>', '.').replace('(', '.').replace(')', '.')):
        spawn_robot(world, 'surveyor', with_lidar(old, new), model_format='sdf')
    assert world.model_names() == []
