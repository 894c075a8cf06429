"""Lasers, cameras and IMUs on robots, without ROS: their maths, their rates, their refusals."""

import math

import numpy as np
import pytest
from repository import model_path, read_file, TEST_MODELS, TINYBOT
from service_tutorial.sim import plugins
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.plugins.imu_sensor import ImuSensor
from service_tutorial.sim.plugins.ray_sensor import RaySensor
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.validation import WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

LASER_ROBOT = model_path('sensor_laser', TEST_MODELS)
WALL = model_path('props/wall', TEST_MODELS)
CAMERA_ROBOT = model_path('sensor_camera', TEST_MODELS)
RED_BOX = model_path('props/red_box', TEST_MODELS)
IMU_ROBOT = model_path('sensor_imu', TEST_MODELS)
# Where sensor_laser.urdf's beams start, standing at the origin.
LASER_ORIGIN = np.array([0.05, 0.0, 0.32])


def laser_world(wall_distance=1.0, **replacements):
    """Return a world with the laser post at the origin and a wall wall_distance ahead."""
    urdf = read_file(LASER_ROBOT)
    for old, new in replacements.items():
        assert old in urdf, old
        urdf = urdf.replace(old, new)
    world = World()
    spawn_robot(world, 'laser', urdf)
    spawn_file(world, 'wall', WALL, position=(LASER_ORIGIN[0] + wall_distance, 0.0, 0.0))
    return world, world.models['laser'].plugin(RaySensor)


def listen(sensor):
    """Switch a sensor on and return the list its readings' times are collected into."""
    times = []
    sensor.listener = lambda reading: times.append(reading.reading_time)
    sensor.set_active(True)
    return times


def yaw(quaternion):
    w, x, y, z = quaternion
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def test_sensor_plugins_are_registered_in_both_generations():
    assert plugins.plugin_class(plugins.kind_of('libgazebo_ros_laser.so')) is RaySensor
    assert plugins.plugin_class(plugins.kind_of('libgazebo_ros_ray_sensor.so')) is RaySensor
    assert plugins.plugin_class(plugins.kind_of('libgazebo_ros_camera.so')) is CameraSensor
    assert plugins.kind_of('libgazebo_ros_imu.so') == 'gazebo_ros_imu'
    assert plugins.kind_of('libgazebo_ros_imu_sensor.so') == 'gazebo_ros_imu_sensor'
    assert plugins.plugin_class('gazebo_ros_imu') is ImuSensor
    assert plugins.plugin_class('gazebo_ros_imu_sensor') is ImuSensor


def test_laser_reads_the_distance_to_a_wall_and_inf_beyond_its_range():
    world, laser = laser_world(1.0)
    config = laser.config
    assert config.samples == 181
    assert config.angle_min == pytest.approx(-math.pi / 2, abs=1e-7)
    assert config.angle_increment == pytest.approx(math.pi / 180, abs=1e-7)
    assert config.angle_min + 180 * config.angle_increment == pytest.approx(config.angle_max)
    times = listen(laser)
    world.step(10)
    assert times, 'an active laser made no scan'
    ranges = laser.ranges
    assert ranges.shape == (181,) and ranges.dtype == np.float32
    # The beam starts inside the post's own collision shapes; it sees the wall only.
    assert ranges[90] == pytest.approx(1.0, abs=0.005)
    # Beams across the 2 m wide wall read 1 / cos(angle); past its ends, nothing within 5 m.
    for beam in (60, 75, 105, 120):
        angle = config.angle_min + beam * config.angle_increment
        assert ranges[beam] == pytest.approx(1.0 / math.cos(angle), abs=0.005)
    assert np.isposinf(ranges[:30]).all() and np.isposinf(ranges[-30:]).all()
    world.set_model_state('wall', position=(LASER_ORIGIN[0] + 5.5, 0.0, 0.0),
                          orientation=(1.0, 0.0, 0.0, 0.0))
    world.step(60)
    assert np.isposinf(laser.ranges).all(), 'a wall beyond range_max must read +inf'


def test_laser_hit_points_lie_on_the_wall_where_the_laser_stood_when_it_scanned():
    world, laser = laser_world(1.0)
    listen(laser)
    world.step(1)
    points = laser.hit_points()
    # Every beam that reads a range ends on the wall's face, 1 m ahead, across its 2 m.
    assert len(points) == np.isfinite(laser.ranges).sum() > 80
    assert points[:, 0] == pytest.approx(LASER_ORIGIN[0] + 1.0, abs=0.005)
    assert points[:, 2] == pytest.approx(LASER_ORIGIN[2], abs=1e-6)
    assert points[:, 1].min() == pytest.approx(-1.0, abs=0.02)
    assert points[:, 1].max() == pytest.approx(1.0, abs=0.02)
    # Moved half a metre to the side, the laser's next scan shows the wall's nearer end.
    world.set_model_state('laser', position=(0.0, 0.5, 0.0), orientation=(1.0, 0.0, 0.0, 0.0))
    world.step(round(laser.period / world.timestep))
    moved = laser.hit_points()
    assert moved[:, 0] == pytest.approx(LASER_ORIGIN[0] + 1.0, abs=0.005)
    assert moved[:, 1].min() == pytest.approx(-1.0, abs=0.02)
    assert moved[:, 1].max() == pytest.approx(1.0, abs=0.02)
    assert len(moved) != len(points)


def test_laser_reads_minus_inf_closer_than_its_minimum_range():
    world, laser = laser_world(0.3, **{'<min>0.05</min>': '<min>0.5</min>'})
    listen(laser)
    world.step(1)
    assert laser.ranges[90] == -math.inf
    assert np.isposinf(laser.ranges[0])


def test_laser_noise_has_the_blocks_spread_and_stays_in_range():
    world, laser = laser_world(1.0, **{
        '<stddev>0.0</stddev>': '<stddev>0.02</stddev>', '<mean>0.0</mean>': '<mean>0.01</mean>',
        '<update_rate>10</update_rate>': '<update_rate>0</update_rate>'})
    centre = []
    laser.listener = lambda sensor: centre.append(float(sensor.ranges[90]))
    laser.set_active(True)
    world.step(500)
    assert len(centre) == 500, 'update_rate 0 scans every physics step'
    assert np.std(centre) == pytest.approx(0.02, rel=0.2)
    assert np.mean(centre) == pytest.approx(1.01, abs=0.005)
    # Noise goes on readings in range only: the beams that see nothing stay +inf.
    assert np.isposinf(laser.ranges[:30]).all()


def test_laser_noise_is_the_same_in_every_run_of_the_same_world():
    def noisy_scans():
        world, laser = laser_world(1.0, **{'<stddev>0.0</stddev>': '<stddev>0.02</stddev>'})
        scans = []
        laser.listener = lambda sensor: scans.append(sensor.ranges.copy())
        laser.set_active(True)
        world.step(200)
        return np.array(scans)

    first, second = noisy_scans(), noisy_scans()
    assert len(first) >= 3
    np.testing.assert_array_equal(first, second)
    assert not np.array_equal(first[0], first[1]), 'each scan draws fresh noise'


def test_laser_resolution_casts_samples_times_resolution_beams_over_the_same_fan():
    world, laser = laser_world(1.0, **{'<resolution>1</resolution>': '<resolution>2</resolution>'})
    config = laser.config
    assert config.samples == 362
    assert (config.angle_min, config.angle_max) == pytest.approx((-math.pi / 2, math.pi / 2))
    listen(laser)
    world.step(1)
    assert laser.ranges.shape == (362,)
    # The middle two beams straddle straight ahead, a quarter of a degree either side.
    assert laser.ranges[180] == pytest.approx(1.0, abs=0.005)
    assert laser.ranges[181] == pytest.approx(1.0, abs=0.005)


def test_laser_scans_at_its_rate_in_simulation_time_only_while_active():
    world, laser = laser_world(1.0)
    world.step(100)
    assert laser.reading_time is None and laser.next_event() == math.inf
    switched_on = world.time
    times = listen(laser)
    world.step(round(1.0 / world.timestep) + 1)
    # 10 Hz: the first scan one step after it was switched on, then every 0.1 s from that one.
    first = switched_on + world.timestep
    assert np.array(times) == pytest.approx(first + 0.1 * np.arange(11), abs=1e-9)
    laser.set_active(False)
    world.step(100)
    assert len(times) == 11 and laser.next_event() == math.inf
    # After a reset of time, an active laser goes on scanning from the new time.
    laser.set_active(True)
    world.step(5)
    world.reset_simulation()
    world.step(1)
    assert times[-1] == pytest.approx(world.timestep)


def test_laser_sees_other_robots_but_not_its_own():
    world, laser = laser_world(3.0)
    listen(laser)
    spawn_file(world, 'other', LASER_ROBOT, position=(1.5, 0.0, 0.0))
    world.step(1)
    # The other post's laser housing (a cylinder of radius 0.04 around x = 1.55).
    assert laser.ranges[90] == pytest.approx(1.55 - 0.04 - LASER_ORIGIN[0], abs=0.005)


def test_camera_sees_the_red_box_ahead_in_the_middle_of_its_image():
    world = World()
    spawn_file(world, 'camera_post', CAMERA_ROBOT)
    spawn_file(world, 'box', RED_BOX, position=(1.5, 0.0, 0.0))
    camera = world.models['camera_post'].plugin(CameraSensor)
    try:
        listen(camera)
        world.step(1)
        image = camera.image.astype(int)
    finally:
        camera.close()
    assert image.shape == (120, 160, 3)

    def red(row, column):
        r, g, b = image[row, column]
        return r > 2 * g and r > 2 * b
    assert red(60, 80), f'the centre is {image[60, 80]}, not red'
    assert not any(red(row, column) for row, column in
                   ((60, 0), (60, 159), (0, 80), (119, 80), (0, 0), (119, 159)))
    # The box is 0.4 m wide at 1.5 m: it spans about 2 * 0.2 / 1.5 * fx pixels.
    config = camera.config
    focal = 160 / 2 / math.tan(1.0 / 2)
    red_columns = [column for column in range(160) if red(60, column)]
    assert len(red_columns) == pytest.approx(2 * (0.2 / (1.5 - 0.2)) * focal, abs=3)
    k = config.intrinsic_matrix()
    assert k[0, 0] == pytest.approx(focal) and k[1, 1] == pytest.approx(focal)
    assert (k[0, 2], k[1, 2]) == pytest.approx((79.5, 59.5))
    assert config.fovy == pytest.approx(math.degrees(2 * math.atan(math.tan(0.5) * 0.75)))


def test_imu_at_rest_reads_gravity_up_and_follows_a_turn():
    world = World(cmd_vel_timeout=0.0)
    spawn_file(world, 'imu_bot', IMU_ROBOT)
    ros1, ros2 = (plugin for plugin in world.models['imu_bot'].plugins
                  if isinstance(plugin, ImuSensor))
    assert (ros1.config.name, ros2.config.name) == ('imu_ros1', 'imu_ros2')
    for imu in (ros1, ros2):
        listen(imu)
    world.step(round(0.5 / world.timestep))
    for imu in (ros1, ros2):
        # REP 145: an IMU at rest measures the floor pushing it up.
        assert imu.linear_acceleration == pytest.approx([0.0, 0.0, 9.81], abs=0.05)
        assert imu.angular_velocity == pytest.approx([0.0, 0.0, 0.0], abs=1e-3)
    start = yaw(world.get_model_state('imu_bot').orientation)
    world.models['imu_bot'].drive().command_velocity(0.0, 0.5)
    turned = 0.0
    while turned < 1.0:
        world.step(1)
        turned = yaw(world.get_model_state('imu_bot').orientation) - start
    truth = yaw(world.get_model_state('imu_bot').orientation)
    assert yaw(ros1.orientation) == pytest.approx(truth, abs=0.01)
    # The ROS 2 IMU sits turned by 90 degrees on the robot.
    assert yaw(ros2.orientation) == pytest.approx(truth + math.pi / 2, abs=0.01)
    assert ros1.angular_velocity[2] == pytest.approx(0.5, abs=0.1)
    assert ros1.covariance('angular_velocity') == pytest.approx([0.0, 0.0, 0.0])


def test_imu_noise_and_its_covariance_come_from_the_block():
    urdf = read_file(IMU_ROBOT).replace('<gaussianNoise>0.0</gaussianNoise>',
                                        '<gaussianNoise>0.05</gaussianNoise>')
    urdf = urdf.replace('<updateRate>50.0</updateRate>', '<updateRate>0</updateRate>')
    world = World()
    spawn_robot(world, 'imu_bot', urdf)
    imu = world.models['imu_bot'].plugins[1]
    samples = []
    imu.listener = lambda sensor: samples.append(sensor.linear_acceleration)
    imu.set_active(True)
    world.step(400)
    assert len(samples) == 400
    assert np.std(np.array(samples)[100:], axis=0) == pytest.approx([0.05] * 3, rel=0.2)
    assert imu.covariance('linear_acceleration') == pytest.approx([0.0025] * 3)
    assert imu.covariance('orientation') == pytest.approx([0.0025] * 3)


def test_a_ros2_imus_per_axis_noise_and_its_covariance_come_from_the_block():
    urdf = read_file(IMU_ROBOT).replace('<stddev>0.0</stddev>', '<stddev>0.02</stddev>')
    urdf = urdf.replace('<update_rate>100</update_rate>', '<update_rate>0</update_rate>')
    world = World()
    spawn_robot(world, 'imu_bot', urdf)
    (ros2,) = (plugin for plugin in world.models['imu_bot'].plugins
               if isinstance(plugin, ImuSensor) and plugin.config.name == 'imu_ros2')
    samples = []
    ros2.listener = lambda sensor: samples.append(sensor.angular_velocity.copy())
    ros2.set_active(True)
    world.step(400)
    assert len(samples) == 400
    # Only the z axis of the angular velocity is noisy, as the block says.
    assert np.std(np.array(samples)[100:], axis=0) == pytest.approx([0.0, 0.0, 0.02],
                                                                    rel=0.2, abs=1e-3)
    assert ros2.covariance('angular_velocity') == pytest.approx([0.0, 0.0, 0.0004])
    assert ros2.covariance('linear_acceleration') == pytest.approx([0.0, 0.0, 0.0])


def test_tinybot_carries_a_laser_a_camera_and_an_imu():
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    tinybot = world.models['tinybot']
    laser, camera, imu = (tinybot.plugin(kind) for kind in (RaySensor, CameraSensor, ImuSensor))
    assert (laser.config.samples, laser.config.update_rate, laser.config.link) == \
        (360, 5.0, 'base_scan')
    assert laser.config.angle_increment == pytest.approx(math.radians(1.0), abs=1e-7)
    assert (camera.config.width, camera.config.height, camera.config.link) == \
        (320, 240, 'camera_link')
    assert imu.config.link == 'base_link'
    world.step(100)
    assert all(sensor.reading_time is None for sensor in (laser, camera, imu)), \
        'a sensor nobody listens to measured'


# ---------------------------------------------------------------- refusals


def refusal_of(path, old, new):
    """Load a sensor robot with one piece of its file replaced; return why it is refused."""
    urdf = read_file(path)
    assert old in urdf
    with pytest.raises(UrdfError) as refusal:
        load_urdf(urdf.replace(old, new))
    return str(refusal.value)


@pytest.mark.parametrize('old, new, message', [
    ('<samples>181</samples>', '<samples>0</samples>',
     "sensor 'front_laser' <ray/scan/horizontal/samples> must be a whole number above 0: "
     "'0'"),
    ('<samples>181</samples>', '<samples>18.5</samples>',
     "sensor 'front_laser' <ray/scan/horizontal/samples> must be a whole number above 0: "
     "'18.5'"),
    ('<update_rate>10</update_rate>', '<update_rate>nan</update_rate>',
     "sensor 'front_laser' <update_rate> contains NaN or infinity: 'nan'"),
    ('<min_angle>-1.5707963</min_angle>', '<min_angle>2</min_angle>',
     "sensor 'front_laser' <ray/scan/horizontal/min_angle> 2 is above its <max_angle> "
     '1.5708'),
    ('<min_angle>-1.5707963</min_angle>', '<min_angle>-1e308</min_angle>',
     "sensor 'front_laser' <ray/scan/horizontal/min_angle> must be within one turn "
     '(+-6.2832 rad): -1e+308'),
    ('<max_angle>1.5707963</max_angle>', '<max_angle>1e308</max_angle>',
     "sensor 'front_laser' <ray/scan/horizontal/max_angle> must be within one turn "
     '(+-6.2832 rad): 1e+308'),
    ('<max_angle>1.5707963</max_angle>', '<max_angle>6</max_angle>',
     "sensor 'front_laser' <ray/scan/horizontal/min_angle> -1.5708 and <max_angle> 6 must be "
     'at most one turn (6.2832 rad) apart: 7.5708 rad'),
    ('<samples>181</samples>', '<samples>1000000000</samples>',
     "sensor 'front_laser' <ray/scan/horizontal/samples> 1000000000 times <resolution> 1 "
     'must give at most 20000 readings per scan'),
    ('<update_rate>10</update_rate>', '<update_rate>1e9</update_rate>',
     "sensor 'front_laser' <update_rate> must be at most 10000 Hz: 1e+09"),
    ('<update_rate>10</update_rate>', '<update_rate>-5</update_rate>',
     "sensor 'front_laser' <update_rate> must be a number of at least 0: '-5'"),
    ('<frame_name>laser_frame</frame_name>', '<frame_name>//a//b//</frame_name>',
     "plugin 'front_laser' <frame_name> '//a//b//' is not a valid frame id: it has an empty "
     "part (a doubled, leading or trailing '/')"),
    ('<frame_name>laser_frame</frame_name>', '<frame_name>laser frame</frame_name>',
     "plugin 'front_laser' <frame_name> 'laser frame' is not a valid frame id: it holds "
     'whitespace or control characters'),
    ('<min>0.05</min>', '<min>-1</min>',
     "sensor 'front_laser' <ray/range/min> must be a number of at least 0: '-1'"),
    ('<max>5.0</max>', '<max>0.01</max>',
     "sensor 'front_laser' <ray/range/max> must be a number above 0.05: '0.01'"),
    ('<stddev>0.0</stddev>', '<stddev>-0.1</stddev>',
     "sensor 'front_laser' <ray/noise/stddev> must be a number of at least 0: '-0.1'"),
    ('<type>gaussian</type>', '<type>salt</type>',
     "sensor 'front_laser' <ray/noise/type> must be gaussian or none: 'salt'"),
    ('<pose>0.05 0 0.02 0 0 0</pose>', '<pose>0.05 0 0.02</pose>',
     "sensor 'front_laser' <pose> must be six numbers (x y z roll pitch yaw): '0.05 0 0.02'"),
    ('<gazebo reference="laser_link">', '<gazebo reference="lazer_link">',
     "sensor 'front_laser' is on link 'lazer_link', which is not a link of the robot"),
    ('<sensor type="ray" name="front_laser">', '<sensor type="camera" name="front_laser">',
     "plugin 'front_laser' (libgazebo_ros_ray_sensor.so) needs a <sensor type=\"ray\"> or "
     "<sensor type=\"gpu_ray\">, but sits in sensor 'front_laser' of type 'camera'"),
])
def test_bad_laser_blocks_are_refused_naming_sensor_tag_and_value(old, new, message):
    assert refusal_of(LASER_ROBOT, old, new) == message
    world = World()
    with pytest.raises(WorldError, match='front_laser'):
        spawn_robot(world, 'laser', read_file(LASER_ROBOT).replace(old, new))
    assert world.model_names() == []


@pytest.mark.parametrize('old, new, message', [
    ('<width>160</width>', '<width>0</width>',
     "sensor 'front_camera' <camera/image/width> must be a whole number above 0: '0'"),
    ('<height>120</height>', '<height>100000</height>',
     "sensor 'front_camera' <camera/image/height> must be at most 4096: 100000"),
    ('<width>160</width>\n          <height>120</height>',
     '<width>4096</width><height>4096</height>',
     "sensor 'front_camera' <camera/image> of 4096x4096 has 16777216 pixels, more than "
     '4194304 (2048x2048)'),
    ('<horizontal_fov>1.0</horizontal_fov>', '<horizontal_fov>3.5</horizontal_fov>',
     "sensor 'front_camera' <camera/horizontal_fov> must be below pi for a pinhole camera: "
     '3.5'),
    ('<far>50</far>', '<far>0.01</far>',
     "sensor 'front_camera' <camera/clip/far> must be a number above 0.02: '0.01'"),
    ('<format>R8G8B8</format>', '<format>BAYER_RGGB8</format>',
     "sensor 'front_camera' <camera/image/format> must be one of R8G8B8, RGB_INT8, B8G8R8, "
     "BGR_INT8, L8, L_INT8: 'BAYER_RGGB8'"),
])
def test_bad_camera_blocks_are_refused(old, new, message):
    assert refusal_of(CAMERA_ROBOT, old, new) == message


@pytest.mark.parametrize('old, new, message', [
    ('<bodyName>base_footprint</bodyName>', '<bodyName>base_foot</bodyName>',
     "IMU plugin 'imu_ros1' <bodyName> 'base_foot' is not a link of the robot"),
    ('<bodyName>base_footprint</bodyName>', '',
     "IMU plugin 'imu_ros1' has no <bodyName>"),
    ('<updateRate>50.0</updateRate>', '<updateRate>1e308</updateRate>',
     "IMU plugin 'imu_ros1' <updateRate> must be at most 10000 Hz: 1e+308"),
    ('<frame_name>imu_link</frame_name>', '<frame_name>/</frame_name>',
     "plugin 'imu_ros2' <frame_name> must name a frame: '/'"),
    ('<gaussianNoise>0.0</gaussianNoise>', '<gaussianNoise>-1</gaussianNoise>',
     "IMU plugin 'imu_ros1' <gaussianNoise> must be one number of at least 0: '-1'"),
    ('<stddev>0.0</stddev>', '<stddev>inf</stddev>',
     "sensor 'imu_ros2' <imu/angular_velocity/z/noise/stddev> contains NaN or infinity: "
     "'inf'"),
])
def test_bad_imu_blocks_are_refused(old, new, message):
    assert refusal_of(IMU_ROBOT, old, new) == message


def test_a_sensor_plugin_outside_a_sensor_is_refused():
    urdf = read_file(IMU_ROBOT).replace('libgazebo_ros_imu.so', 'libgazebo_ros_ray_sensor.so')
    with pytest.raises(UrdfError, match=r"plugin 'imu_ros1' \(libgazebo_ros_ray_sensor.so\) "
                       r'is a laser plugin: it belongs in a <sensor type="ray">'):
        load_urdf(urdf)
