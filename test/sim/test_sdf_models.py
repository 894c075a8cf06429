"""
SDF models, read as gz-sim reads them: poses, frames, masses, inertias and axes by hand.

The suite's own SDF files (test/models/sdf, written from the SDF specification) are spawned
into a ROS-free World, and what MuJoCo makes of them is compared with values worked out here
by hand from the files: each link where its chain of relative_to frames puts it, each mass
and inertia as written (SDF's defaults where nothing is), each joint axis in the frame its
SDF version says.
"""

import math
import os

import mujoco
import numpy as np
import pytest
from repository import TEST_MODELS
from service_tutorial.sim.description_formats import FORMATS
from service_tutorial.sim.plugins.gz_diff_drive import GzDiffDrive
from service_tutorial.sim.robot_files import read_uri
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

SDF_MODELS = os.path.join(TEST_MODELS, 'sdf', 'models')
ROVER = os.path.join(SDF_MODELS, 'rover', 'model.sdf')
PAVILION = os.path.join(SDF_MODELS, 'pavilion')
QUARTER_TURN = math.pi / 2


@pytest.fixture(autouse=True)
def resource_path(monkeypatch):
    """Find the suite's model folders by model://, as GZ_SIM_RESOURCE_PATH finds a user's."""
    monkeypatch.setenv('GZ_SIM_RESOURCE_PATH', SDF_MODELS)


def body(world, name):
    """Return the id of a body of the world's compiled model."""
    return mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_BODY, name)


def joint(world, name):
    """Return the id of a joint of the world's compiled model."""
    return mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_JOINT, name)


def world_inertia(world, name):
    """Return a body's inertia tensor about its centre of mass, in the world's axes."""
    index = body(world, name)
    rotation = world.data.ximat[index].reshape(3, 3)
    return rotation @ np.diag(world.model.body_inertia[index]) @ rotation.T


def sdf_model(body_xml, version='1.8', name='m'):
    """Return SDF text of one model."""
    return f'<sdf version="{version}"><model name="{name}">{body_xml}</model></sdf>'


def box_link(name, pose='', extra=''):
    """Return a link with a 0.1 m box and a mass of 1 kg, posed as given."""
    return (f'<link name="{name}">{pose}<inertial><mass>1</mass><inertia><ixx>0.01</ixx>'
            '<iyy>0.01</iyy><izz>0.01</izz></inertia></inertial><collision name="c">'
            '<geometry><box><size>0.1 0.1 0.1</size></box></geometry></collision>'
            f'{extra}</link>')


# --- the rover: a wheeled robot, STL meshes, a chain of frames, a nested model ------------

def test_the_rovers_links_stand_where_their_chains_of_frames_put_them():
    world = World()
    spawn_file(world, 'rover', ROVER, position=(1.0, 2.0, 0.0))
    positions = {name: world.data.xpos[body(world, 'rover::' + name)]
                 for name in ('chassis', 'left_wheel', 'right_wheel', 'caster', 'mast::pole',
                              'beacon')}
    # chassis: 0.08 up the model frame, which stands at the spawn pose (1, 2, 0).
    assert positions['chassis'] == pytest.approx([1.0, 2.0, 0.08])
    # axle: -0.05 along the chassis; left_hub: 0.2 to the left of the axle; left_wheel: at it.
    assert positions['left_wheel'] == pytest.approx([1.0 - 0.05, 2.0 + 0.2, 0.08])
    assert positions['right_wheel'] == pytest.approx([0.95, 1.8, 0.08])
    assert positions['caster'] == pytest.approx([1.15, 2.0, 0.08 - 0.04])
    # mast: (-0.1, 0, 0.05) from the chassis; its pole 0.15 up the mast frame.
    assert positions['mast::pole'] == pytest.approx([0.9, 2.0, 0.08 + 0.05 + 0.15])
    # beacon: 0.02 above mast::top, which is 0.15 above the pole.
    assert positions['beacon'] == pytest.approx([0.9, 2.0, 0.28 + 0.15 + 0.02])
    # The wheels are turned -90 degrees about x by left_hub's and their own poses: their
    # cylinders' axes, z of their frames, point along the world's y.
    for wheel in ('left_wheel', 'right_wheel'):
        z_axis = world.data.xmat[body(world, 'rover::' + wheel)].reshape(3, 3)[:, 2]
        assert z_axis == pytest.approx([0.0, 1.0, 0.0], abs=1e-9)


def test_the_rovers_masses_and_inertias_are_as_written_or_sdfs_defaults():
    world = World()
    rover = spawn_file(world, 'rover', ROVER)
    masses = {name: world.model.body_mass[body(world, 'rover::' + name)]
              for name in rover.description.links}
    # The beacon has no <inertial>: SDF gives it 1 kg and an identity inertia.
    assert masses == pytest.approx({'chassis': 4.0, 'left_wheel': 0.5, 'right_wheel': 0.5,
                                    'caster': 0.1, 'mast::pole': 0.1, 'beacon': 1.0})
    # The chassis's inertial frame is 0.02 forward and turned 90 degrees about z: its ixx
    # (0.02) lies along the world's y, its iyy (0.05) along x.
    assert world_inertia(world, 'rover::chassis') == pytest.approx(
        np.diag([0.05, 0.02, 0.06]), abs=1e-9)
    centre = world.data.xipos[body(world, 'rover::chassis')]
    assert centre == pytest.approx([0.02, 0.0, 0.08])
    # The wheels' izz is about their axle, which lies along the world's y.
    assert world_inertia(world, 'rover::left_wheel') == pytest.approx(
        np.diag([0.001, 0.0016, 0.001]), abs=1e-12)
    assert world_inertia(world, 'rover::beacon') == pytest.approx(np.eye(3))


def test_the_rovers_joint_axes_limits_and_dynamics():
    world = World()
    rover = spawn_file(world, 'rover', ROVER, orientation=(math.cos(QUARTER_TURN / 2), 0.0,
                                                           0.0, math.sin(QUARTER_TURN / 2)))
    assert rover.description.joints == ('left_wheel_joint', 'right_wheel_joint',
                                        'caster_joint')
    # left: 0 0 1 in the joint frame, which is the wheel's (turned -90 degrees about x): the
    # model's y. right: 0 1 0 expressed in __model__. The model is turned 90 degrees about z,
    # so both lie along the world's -x, through the wheel centres.
    for name, anchor in (('left_wheel_joint', (-0.2, -0.05, 0.08)),
                         ('right_wheel_joint', (0.2, -0.05, 0.08))):
        index = joint(world, 'rover::' + name)
        assert world.data.xaxis[index] == pytest.approx([-1.0, 0.0, 0.0], abs=1e-9)
        assert world.data.xanchor[index] == pytest.approx(anchor, abs=1e-9)
        # No limits (SDF's 1e16 is none), an effort of 5 N m.
        assert not world.model.jnt_limited[index]
        assert world.model.jnt_actfrcrange[index] == pytest.approx([-5.0, 5.0])
    assert world.model.dof_damping[world.model.jnt_dofadr[joint(
        world, 'rover::left_wheel_joint')]] == pytest.approx(0.01)
    caster = joint(world, 'rover::caster_joint')
    assert world.model.jnt_type[caster] == mujoco.mjtJoint.mjJNT_BALL
    # The mast and the beacon are welded to the chassis by fixed joints: one body group.
    assert world.model.body_weldid[body(world, 'rover::beacon')] == \
        world.model.body_weldid[body(world, 'rover::chassis')]


def test_the_rover_stands_where_it_was_asked_and_carries_its_diff_drive():
    world = World()
    yaw = 0.7
    rover = spawn_file(world, 'rover', ROVER, position=(-1.5, 0.5, 0.0),
                       orientation=(math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)))
    world.step(round(1.0 / world.timestep))
    state = world.get_model_state('rover')
    assert state.position == pytest.approx([-1.5, 0.5, 0.08], abs=2e-3)
    assert state.orientation == pytest.approx([math.cos(yaw / 2), 0.0, 0.0,
                                               math.sin(yaw / 2)], abs=2e-3)
    description = rover.description
    assert description.ignored_plugins == () and description.notes == ()
    (drive,) = rover.plugins
    assert isinstance(drive, GzDiffDrive)
    assert (drive.config.wheel_separation, drive.config.wheel_radius) == (0.4, 0.08)


# --- the pavilion: a static model folder by model://, DAE meshes, cylinders ----------------

def test_a_static_model_folder_by_model_uri_is_welded_where_it_stands():
    robot = read_uri('model://pavilion', None)
    # model.config names 1.6, 1.8 and 1.12 files: the newest the world reads is 1.8's.
    assert (robot.model_format, robot.robot_name) == ('sdf', 'pavilion')
    assert robot.base_dir == PAVILION
    world = World()
    pavilion = spawn_robot(world, 'pavilion', robot.text, base_dir=robot.base_dir,
                           model_format='sdf', position=(5.0, 0.0, 0.0))
    assert pavilion.anchored and pavilion.description.joints == ()
    model = world.model
    geoms = {}
    for index in range(model.ngeom):
        if model.geom_bodyid[index] > 0 and model.geom_group[index] == 3:
            geoms.setdefault(model.body(model.geom_bodyid[index]).name, []).append(index)
    assert sorted(geoms) == sorted(f'pavilion::{name}' for name in (
        'slab', 'column_ne', 'column_nw', 'column_sw', 'column_se', 'roof'))
    column, = geoms['pavilion::column_ne']
    assert model.geom_type[column] == mujoco.mjtGeom.mjGEOM_CYLINDER
    assert model.geom_size[column][:2] == pytest.approx([0.1, 1.0])  # radius, half length
    assert world.data.geom_xpos[column] == pytest.approx([6.8, 1.3, 1.1])
    roof, = geoms['pavilion::roof']
    assert model.geom_type[roof] == mujoco.mjtGeom.mjGEOM_MESH
    # The Collada box of 0.1 x 0.06 x 0.04 m (its unit is the centimetre), scaled 40 50 1.
    lower, upper = mesh_extent(world, roof)
    assert upper - lower == pytest.approx([4.0, 3.0, 0.04], abs=1e-5)
    assert pavilion.description.mesh_files == (os.path.join(PAVILION, 'meshes', 'roof.dae'),) * 2
    world.step(100)
    assert world.data.geom_xpos[column] == pytest.approx([6.8, 1.3, 1.1])


def mesh_extent(world, geom):
    """Return the lower and upper corners of a mesh geom's vertices, in the world frame."""
    model = world.model
    mesh = model.geom_dataid[geom]
    start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    vertices = model.mesh_vert[start:start + count]
    rotation = world.data.geom_xmat[geom].reshape(3, 3)
    placed = vertices @ rotation.T + world.data.geom_xpos[geom]
    return placed.min(axis=0), placed.max(axis=0)


# --- SDF versions: the frames of joint axes and of poses ---------------------------------

HINGED = ('<link name="base"><pose>0 0 1 0 0 0</pose><inertial><mass>1</mass></inertial>'
          '</link><link name="arm"><pose>1 0 1 0 0 1.5707963267948966</pose><inertial><mass>1'
          '</mass></inertial></link><joint name="hinge" type="revolute"><parent>base</parent>'
          '<child>arm</child><pose>0 0 0 {joint_roll} 0 0</pose><axis><xyz>1 0 0</xyz>{flag}'
          '<limit><lower>-1</lower><upper>1</upper></limit></axis></joint>')


@pytest.mark.parametrize('version, flag, expected', [
    # SDF 1.4: the axis is in the model frame.
    ('1.4', '', (1.0, 0.0, 0.0)),
    # 1.5 and 1.6: in the joint frame (the arm's, turned 90 degrees about z), unless
    # use_parent_model_frame.
    ('1.5', '', (0.0, 1.0, 0.0)),
    ('1.6', '<use_parent_model_frame>true</use_parent_model_frame>', (1.0, 0.0, 0.0)),
    ('1.6', '<use_parent_model_frame>false</use_parent_model_frame>', (0.0, 1.0, 0.0)),
    # 1.7 on: in the joint frame; use_parent_model_frame is no longer read.
    ('1.7', '', (0.0, 1.0, 0.0)),
    ('1.11', '', (0.0, 1.0, 0.0)),
])
def test_a_joint_axis_is_in_the_frame_its_version_says(version, flag, expected):
    world = World()
    text = sdf_model(HINGED.format(joint_roll=0.5, flag=flag), version)
    spawn_robot(world, 'arm', text, model_format='sdf', position=(0.0, 0.0, 0.0))
    index = joint(world, 'arm::hinge')
    # The joint frame is the arm's turned 0.5 rad about its x; x itself does not move.
    assert world.data.xaxis[index] == pytest.approx(expected, abs=1e-9)
    assert world.data.xanchor[index] == pytest.approx([1.0, 0.0, 1.0])
    assert world.model.jnt_range[index] == pytest.approx([-1.0, 1.0])


def test_an_expressed_in_frame_turns_the_axis():
    text = sdf_model('<frame name="tilted"><pose>0 0 0 0 0 0.5</pose></frame>'
                     + HINGED.format(joint_roll=0.0, flag='').replace(
                         '<xyz>', '<xyz expressed_in="tilted">'), '1.8')
    world = World()
    spawn_robot(world, 'arm', text, model_format='sdf')
    assert world.data.xaxis[joint(world, 'arm::hinge')] == pytest.approx(
        [math.cos(0.5), math.sin(0.5), 0.0], abs=1e-9)


def test_sdf_1_9_poses_in_degrees_and_as_quaternions():
    half = math.sqrt(0.5)
    text = sdf_model(
        box_link('base')
        + box_link('a', '<pose degrees="true">1 0 0 0 0 90</pose>')
        + box_link('b', f'<pose rotation_format="quat_xyzw">0 1 0 0 0 {half} {half}</pose>')
        + '<joint name="ja" type="fixed"><parent>base</parent><child>a</child></joint>'
        + '<joint name="jb" type="fixed"><parent>base</parent><child>b</child></joint>', '1.9')
    world = World()
    spawn_robot(world, 'm', text, model_format='sdf', position=(0.0, 0.0, 2.0))
    for name, position in (('a', (1.0, 0.0, 2.0)), ('b', (0.0, 1.0, 2.0))):
        index = body(world, 'm::' + name)
        assert world.data.xpos[index] == pytest.approx(position)
        assert world.data.xquat[index] == pytest.approx([half, 0.0, 0.0, half])


def test_a_pose_frame_of_sdf_1_6_is_read_as_relative_to():
    # sdformat's conversion to 1.7 renames pose@frame to relative_to; '' is the default.
    text = sdf_model(box_link('base', "<pose frame=''>0 0 1 0 0 0</pose>")
                     + box_link('top', "<pose frame='base'>0 0 0.5 0 0 0</pose>")
                     + '<joint name="j" type="fixed"><parent>base</parent><child>top</child>'
                     '</joint>', '1.6')
    world = World()
    spawn_robot(world, 'm', text, model_format='sdf')
    assert world.data.xpos[body(world, 'm::top')] == pytest.approx([0.0, 0.0, 1.5])


def test_a_joint_to_the_world_anchors_the_model():
    text = sdf_model(box_link('door', '<pose>0 0 1 0 0 0</pose>')
                     + '<joint name="hinge" type="revolute"><parent>world</parent><child>door'
                     '</child><axis><xyz>0 0 1</xyz></axis></joint>')
    world = World()
    door = spawn_robot(world, 'door', text, model_format='sdf', position=(2.0, 0.0, 0.0))
    assert door.anchored and door.description.joints == ('hinge',)
    world.step(200)
    assert world.get_model_state('door').position == pytest.approx([2.0, 0.0, 1.0])


def test_universal_and_prismatic_joints():
    text = sdf_model(box_link('base') + box_link('slider', '<pose>0 0 0.5 0 0 0</pose>')
                     + box_link('head', '<pose>0 0 1 0 0 0</pose>')
                     + '<joint name="rail" type="prismatic"><parent>base</parent><child>slider'
                     '</child><axis><xyz>0 0 1</xyz><limit><lower>0</lower><upper>0.3</upper>'
                     '</limit></axis></joint><joint name="wrist" type="universal"><parent>'
                     'slider</parent><child>head</child><axis><xyz>1 0 0</xyz></axis><axis2>'
                     '<xyz>0 1 0</xyz></axis2></joint>')
    world = World()
    robot = spawn_robot(world, 'm', text, model_format='sdf', position=(0.0, 0.0, 1.0))
    assert robot.description.joints == ('rail', 'wrist', 'wrist_axis2')
    assert world.model.jnt_type[joint(world, 'm::rail')] == mujoco.mjtJoint.mjJNT_SLIDE
    assert world.model.jnt_range[joint(world, 'm::rail')] == pytest.approx([0.0, 0.3])
    assert world.data.xaxis[joint(world, 'm::wrist_axis2')] == pytest.approx([0, 1, 0])


def test_gazebos_material_scripts_and_colours():
    text = sdf_model('<link name="l"><visual name="grey"><geometry><sphere><radius>0.1</radius>'
                     '</sphere></geometry><material><script><name>Gazebo/Red</name></script>'
                     '</material></visual><visual name="clear"><geometry><box><size>1 1 1'
                     '</size></box></geometry><transparency>0.5</transparency><material>'
                     '<diffuse>0 1 0 1</diffuse></material></visual></link>')
    description = FORMATS['sdf'].load(text)
    spec = description.spec.compile()
    assert spec.geom_rgba[0] == pytest.approx([1.0, 0.0, 0.0, 1.0])
    assert spec.geom_rgba[1] == pytest.approx([0.0, 1.0, 0.0, 0.5])
