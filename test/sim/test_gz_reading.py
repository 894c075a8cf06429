"""
What the world reads of Gazebo Harmonic's files before it simulates a system: names and places.

gz topics and frames as gz-transport and ros_gz name them; a world's <spherical_coordinates>
as gz-math turns a world position into latitude, longitude and altitude; an SDF model's
<plugin>s and <sensor>s kept as blocks for the plugins, and named when the world does not
simulate them.
"""

import math

import pytest
from service_tutorial.sim import plugins
from service_tutorial.sim.geodesy import SphericalCoordinates
from service_tutorial.sim.plugins import gz_names
from service_tutorial.sim.plugins.diff_drive import DiffDrive
from service_tutorial.sim.sdf.world import read_sdf_world
from service_tutorial.sim.validation import DescriptionError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_robot

# One metre along the equator, in degrees of longitude (WGS84's equatorial radius).
EQUATOR_DEGREE_PER_METRE = 360.0 / (2.0 * math.pi * 6378137.0)

WHEELS = """
  <link name="body">
    <pose>0 0 0.1 0 0 0</pose>
    <inertial><mass>2</mass><inertia><ixx>0.02</ixx><iyy>0.02</iyy><izz>0.02</izz></inertia>
    </inertial>
    <collision name="c"><geometry><box><size>0.3 0.2 0.1</size></box></geometry></collision>
    {sensors}
  </link>
  <link name="left"><pose>0 0.12 0.05 -1.5708 0 0</pose>
    <collision name="c"><geometry><cylinder><radius>0.05</radius><length>0.02</length>
    </cylinder></geometry></collision></link>
  <link name="right"><pose>0 -0.12 0.05 -1.5708 0 0</pose>
    <collision name="c"><geometry><cylinder><radius>0.05</radius><length>0.02</length>
    </cylinder></geometry></collision></link>
  <joint name="left_joint" type="continuous"><parent>body</parent><child>left</child>
    <axis><xyz>0 0 1</xyz></axis></joint>
  <joint name="right_joint" type="continuous"><parent>body</parent><child>right</child>
    <axis><xyz>0 0 1</xyz></axis></joint>
"""


def sdf_robot(plugins_xml='', sensors=''):
    """Return an SDF model on two wheels with these plugins, and sensors on its body."""
    return (f'<sdf version="1.9"><model name="cart">{WHEELS.format(sensors=sensors)}'
            f'{plugins_xml}</model></sdf>')


@pytest.mark.parametrize('written, topic', [
    ('cmd_vel', '/cmd_vel'),
    ('/model/tb3/cmd_vel', '/model/tb3/cmd_vel'),
    ('my robot/cmd vel', '/my_robot/cmd_vel'),
    ('~/scan@x', '/scanx'),
    ('a//b', '/ab'),
    ('scan/', '/scan'),
    ('a:=b', '/ab'),
    ('', None),
    ('/', None),
    ('@~', None),
])
def test_gz_topics_are_made_valid_as_gz_transport_makes_them(written, topic):
    assert gz_names.valid_topic(written) == topic


def test_a_system_takes_its_first_valid_candidate():
    assert gz_names.first_valid_topic('@', None, '/model/m/cmd_vel') == '/model/m/cmd_vel'
    assert gz_names.first_valid_topic('odom', '/model/m/odometry') == '/odom'
    assert gz_names.first_valid_topic('', '/') is None


def test_default_topics_and_frames_name_the_world_model_link_and_sensor():
    assert gz_names.model_topic('tb3', 'cmd_vel') == '/model/tb3/cmd_vel'
    assert gz_names.world_model_topic('empty', 'tb3', 'joint_state') == \
        '/world/empty/model/tb3/joint_state'
    assert gz_names.sensor_topic('empty', 'tb3', 'base_scan', 'hls_lfcd_lds', 'scan') == \
        '/world/empty/model/tb3/link/base_scan/sensor/hls_lfcd_lds/scan'
    # A link of a nested model: the model's scope is a model of its own in the topic.
    assert gz_names.sensor_topic('w', 'rover', 'mast::pole', 'cam') == \
        '/world/w/model/rover/model/mast/link/pole/sensor/cam'
    assert gz_names.sensor_frame('tb3', 'imu_link', 'tb3_imu') == 'tb3/imu_link/tb3_imu'
    assert gz_names.sensor_frame('rover', 'mast::pole', 'cam') == 'rover/mast/pole/cam'
    assert gz_names.model_frame('tb3', 'odom') == 'tb3/odom'


def test_gz_system_filenames_are_known_however_written():
    for filename in ('gz-sim-diff-drive-system', 'libgz-sim8-diff-drive-system.so',
                     'ignition-gazebo-diff-drive-system',
                     'libignition-gazebo6-diff-drive-system.so'):
        assert plugins.gz_system(filename) == 'gz-sim-diff-drive-system', filename
    assert plugins.gz_system('libgazebo_ros_diff_drive.so') is None
    assert plugins.kind_of('gz-sim-pose-publisher-system') is None
    assert plugins.kind_of('libgazebo_ros_diff_drive.so') == 'gazebo_ros_diff_drive'
    assert plugins.sensor_kind('thermal_camera') is None


def test_the_world_origin_is_the_reference_latitude_longitude_and_elevation():
    place = SphericalCoordinates(latitude_deg=-22.986687, longitude_deg=-43.202501,
                                 elevation=25.0, heading_deg=0.0)
    latitude, longitude, altitude = place.spherical_from_local((0.0, 0.0, 0.0))
    assert (latitude, longitude) == pytest.approx((-22.986687, -43.202501), abs=1e-9)
    assert altitude == pytest.approx(25.0, abs=1e-6)


def test_east_is_x_and_a_heading_turns_it_counter_clockwise():
    equator = SphericalCoordinates()
    latitude, longitude, altitude = equator.spherical_from_local((100.0, 0.0, 2.0))
    assert longitude == pytest.approx(100.0 * EQUATOR_DEGREE_PER_METRE, rel=1e-6)
    assert latitude == pytest.approx(0.0, abs=1e-9)
    assert altitude == pytest.approx(2.0, abs=1e-3)
    # Turned 90 degrees, the world's x axis points north.
    turned = SphericalCoordinates(heading_deg=90.0)
    latitude, longitude, _ = turned.spherical_from_local((100.0, 0.0, 0.0))
    assert longitude == pytest.approx(0.0, abs=1e-9) and latitude > 8e-4
    assert turned.global_from_local_velocity((1.0, 0.0, 0.5)) == \
        pytest.approx((0.0, 1.0, 0.5), abs=1e-12)


def sdf_world(extra):
    return (f'<sdf version="1.9"><world name="plain">{extra}<include><uri>'
            'https://fuel.gazebosim.org/1.0/OpenRobotics/models/Ground Plane</uri></include>'
            '</world></sdf>')


def test_an_sdf_world_says_where_it_lies_on_the_earth():
    world = read_sdf_world(sdf_world(
        '<spherical_coordinates><surface_model>EARTH_WGS84</surface_model>'
        '<world_frame_orientation>ENU</world_frame_orientation><latitude_deg>47.3977'
        '</latitude_deg><longitude_deg>8.5456</longitude_deg><elevation>488</elevation>'
        '<heading_deg>0</heading_deg></spherical_coordinates>'),
        'text', None, None, None)
    assert world.spherical_coordinates == SphericalCoordinates(47.3977, 8.5456, 488.0, 0.0)
    assert world.not_simulated == ()
    assert read_sdf_world(sdf_world(''), 'text', None, None, None).spherical_coordinates is None
    moon = read_sdf_world(sdf_world('<spherical_coordinates><surface_model>MOON_SCS'
                                    '</surface_model></spherical_coordinates>'),
                          'text', None, None, None)
    assert moon.not_simulated == ("<surface_model> 'MOON_SCS' (taken as EARTH_WGS84) of "
                                  "<spherical_coordinates> of world 'plain'",)


@pytest.mark.parametrize('value', ['nan', '91', 'north'])
def test_an_absurd_latitude_is_refused(value):
    with pytest.raises(DescriptionError, match='latitude_deg'):
        read_sdf_world(sdf_world(f'<spherical_coordinates><latitude_deg>{value}'
                                 '</latitude_deg></spherical_coordinates>'),
                       'text', None, None, None)


def test_a_world_keeps_its_name_and_place_until_another_is_loaded():
    place = SphericalCoordinates(latitude_deg=10.0)
    world = World(name='plain', spherical_coordinates=place)
    assert (world.name, world.spherical_coordinates) == ('plain', place)
    world.load(None)
    assert (world.name, world.spherical_coordinates) == ('default', None)


def test_unknown_systems_and_sensors_of_an_sdf_model_are_named_and_it_spawns():
    world = World()
    text = sdf_robot(
        '<plugin filename="gz-sim-pose-publisher-system" name="gz::sim::systems::PosePublisher">'
        '<publish_link_pose>true</publish_link_pose></plugin>',
        '<sensor name="thermo" type="thermal_camera"><camera><image><width>8</width>'
        '</image></camera></sensor>')
    model = spawn_robot(world, 'cart', text, model_format='sdf', position=(0.0, 0.0, 0.0))
    description = model.description
    assert description.ignored_plugins == ('gz-sim-pose-publisher-system',)
    assert description.notes == (
        "not simulated, ignored: <plugin> 'gz-sim-pose-publisher-system' of model 'cart'; "
        "<sensor type='thermal_camera'> of sensor 'thermo' of link 'body' of model 'cart'",)
    assert model.plugins == ()
    world.step(100)


def test_an_sdf_model_carries_gazebo_classic_plugins_as_a_urdf_does():
    # A Gazebo 11 model.sdf (TurtleBot3's for Gazebo Classic) names gazebo_ros's plugins.
    world = World()
    text = sdf_robot('<plugin name="drive" filename="libgazebo_ros_diff_drive.so">'
                     '<left_joint>left_joint</left_joint><right_joint>right_joint</right_joint>'
                     '<wheel_separation>0.24</wheel_separation><wheel_diameter>0.1'
                     '</wheel_diameter></plugin>')
    model = spawn_robot(world, 'cart', text, model_format='sdf', position=(0.0, 0.0, 0.0))
    (drive,) = model.plugins
    assert isinstance(drive, DiffDrive)
    assert drive.config.wheel_separation == 0.24
    assert model.description.actuators == ('left_joint_drive', 'right_joint_drive')


def test_a_plugin_of_a_nested_model_is_named_as_not_simulated():
    text = ('<sdf version="1.9"><model name="outer">'
            f'<model name="cart">{WHEELS.format(sensors="")}'
            '<plugin name="drive" filename="libgazebo_ros_diff_drive.so"/></model>'
            '</model></sdf>')
    model = spawn_robot(World(), 'outer', text, model_format='sdf')
    assert model.plugins == ()
    assert model.description.ignored_plugins == ('libgazebo_ros_diff_drive.so',)
    assert "<plugin> 'libgazebo_ros_diff_drive.so' of nested model 'outer::cart'" in \
        model.description.notes[0]
