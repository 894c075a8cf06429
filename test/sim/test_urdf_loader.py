"""URDF loading: geometry, joints, inertia, Gazebo blocks, and every input that is refused."""

import io
import math
import os
import re

import mujoco
import numpy as np
import pytest
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import diff_drive
from service_tutorial.sim.plugins import drive_config
from service_tutorial.sim.plugins.drive_config import ODOMETRY_SOURCE_ENCODER
from service_tutorial.sim.plugins.drive_config import ODOMETRY_SOURCE_WORLD
from service_tutorial.sim.urdf import builder
from service_tutorial.sim.urdf import hardened_xml
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.validation import WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_robot

INERTIAL = ('<inertial><mass value="{mass}"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
            'ixy="0" ixz="0" iyz="0"/></inertial>')


def link(name, body='', mass='1.0'):
    return f'<link name="{name}">{INERTIAL.format(mass=mass)}{body}</link>'


def joint(name, parent, child, kind='fixed', extra=''):
    return (f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/>{extra}</joint>')


def robot(*parts, name='test_robot'):
    return f'<robot name="{name}">{"".join(parts)}</robot>'


def compiled(description):
    return description.spec.compile()


def body_geoms(model, body_name, group):
    body_id = model.body(body_name).id
    return [index for index in range(model.ngeom)
            if model.geom_bodyid[index] == body_id and model.geom_group[index] == group]


GEOMETRY_ROBOT = robot(
    '<material name="teal"><color rgba="0 0.5 0.5 1"/></material>',
    link('base', '<visual><geometry><box size="0.4 0.2 0.1"/></geometry>'
                 '<material name="teal"/></visual>'
                 '<visual><origin xyz="0 0 0.1"/><geometry><sphere radius="0.05"/></geometry>'
                 '<material name="red"><color rgba="1 0 0 1"/></material></visual>'
                 '<collision><geometry><box size="0.4 0.2 0.1"/></geometry></collision>'),
    link('wheel', '<visual><geometry><cylinder radius="0.1" length="0.04"/></geometry></visual>'
                  '<collision><geometry><cylinder radius="0.1" length="0.04"/></geometry>'
                  '</collision>'),
    joint('axle', 'base', 'wheel', 'continuous',
          '<origin xyz="0 0.15 0" rpy="1.5707963267948966 0 0"/><axis xyz="0 0 2"/>'
          '<dynamics damping="0.3" friction="0.05"/>'),
    link('arm'),
    joint('shoulder', 'base', 'arm', 'revolute',
          '<axis xyz="0 1 0"/><limit lower="-0.5" upper="1.2" effort="5" velocity="1"/>'),
    link('slider'),
    joint('rail', 'base', 'slider', 'prismatic',
          '<axis xyz="1 0 0"/><limit lower="0" upper="0.3" effort="5" velocity="1"/>'))


def test_geometry_types_sizes_and_groups():
    model = compiled(load_urdf(GEOMETRY_ROBOT))
    box, sphere = body_geoms(model, 'base', builder.VISUAL_GROUP)
    assert model.geom_type[box] == mujoco.mjtGeom.mjGEOM_BOX
    np.testing.assert_allclose(model.geom_size[box], [0.2, 0.1, 0.05])
    assert model.geom_type[sphere] == mujoco.mjtGeom.mjGEOM_SPHERE
    assert model.geom_size[sphere][0] == pytest.approx(0.05)
    np.testing.assert_allclose(model.geom_pos[sphere], [0.0, 0.0, 0.1])
    (cylinder,) = body_geoms(model, 'wheel', builder.COLLISION_GROUP)
    assert model.geom_type[cylinder] == mujoco.mjtGeom.mjGEOM_CYLINDER
    np.testing.assert_allclose(model.geom_size[cylinder][:2], [0.1, 0.02])


def test_visuals_do_not_collide_and_collisions_do():
    model = compiled(load_urdf(GEOMETRY_ROBOT))
    for index in body_geoms(model, 'base', builder.VISUAL_GROUP):
        assert model.geom_contype[index] == 0 and model.geom_conaffinity[index] == 0
    for index in body_geoms(model, 'base', builder.COLLISION_GROUP):
        assert model.geom_contype[index] == 1 and model.geom_conaffinity[index] == 1


def test_visual_colours_named_inline_and_default():
    model = compiled(load_urdf(GEOMETRY_ROBOT))
    box, sphere = body_geoms(model, 'base', builder.VISUAL_GROUP)
    np.testing.assert_allclose(model.geom_rgba[box], [0.0, 0.5, 0.5, 1.0])
    np.testing.assert_allclose(model.geom_rgba[sphere], [1.0, 0.0, 0.0, 1.0])
    (disc,) = body_geoms(model, 'wheel', builder.VISUAL_GROUP)
    np.testing.assert_allclose(model.geom_rgba[disc], builder.DEFAULT_VISUAL_RGBA)


def test_joints_types_limits_axes_and_dynamics():
    description = load_urdf(GEOMETRY_ROBOT)
    assert description.joints == ('axle', 'shoulder', 'rail')
    model = compiled(description)
    axle, shoulder, rail = (model.joint(name) for name in description.joints)
    assert axle.type == mujoco.mjtJoint.mjJNT_HINGE and not model.jnt_limited[axle.id]
    np.testing.assert_allclose(model.jnt_axis[axle.id], [0.0, 0.0, 1.0])
    assert model.dof_damping[model.jnt_dofadr[axle.id]] == pytest.approx(0.3)
    assert model.dof_frictionloss[model.jnt_dofadr[axle.id]] == pytest.approx(0.05)
    assert shoulder.type == mujoco.mjtJoint.mjJNT_HINGE and model.jnt_limited[shoulder.id]
    np.testing.assert_allclose(model.jnt_range[shoulder.id], [-0.5, 1.2])
    assert rail.type == mujoco.mjtJoint.mjJNT_SLIDE and model.jnt_limited[rail.id]
    np.testing.assert_allclose(model.jnt_range[rail.id], [0.0, 0.3])


def test_joint_origin_places_and_turns_the_child():
    model = compiled(load_urdf(GEOMETRY_ROBOT))
    wheel = model.body('wheel').id
    np.testing.assert_allclose(model.body_pos[wheel], [0.0, 0.15, 0.0], atol=1e-12)
    half = math.pi / 4.0
    np.testing.assert_allclose(model.body_quat[wheel], [math.cos(half), math.sin(half), 0, 0],
                               atol=1e-9)


def rotation(quaternion):
    matrix = np.zeros(9)
    mujoco.mju_quat2Mat(matrix, np.asarray(quaternion, dtype=float))
    return matrix.reshape(3, 3)


# Turns about each axis and all three, a pitch of a quarter turn (gimbal lock) among them.
TURNS = ['0.3 0 0', '0 -1.1 0', '0 0 2.9', '0.4 -0.9 2.2', '-3 1.5707963267948966 0.5']


def test_every_origin_is_the_pose_yourdfpy_reads():
    """Joint, inertial and per-visual and per-collision origins land where yourdfpy puts them."""
    yourdfpy = pytest.importorskip('yourdfpy')
    parts = ['<link name="base"/>']
    for index, rpy in enumerate(TURNS):
        origin = f'<origin xyz="{index} {-index / 2} 0.{index}" rpy="{rpy}"/>'
        geoms = ''.join(
            f'<{kind}><origin xyz="0.{index} {number} 0" rpy="{TURNS[-1 - index]}"/>'
            f'<geometry><box size="0.1 0.2 0.3"/></geometry></{kind}>'
            for kind in ('visual', 'collision') for number in (1, 2))
        parts += [f'<link name="l{index}"><inertial>{origin}<mass value="1"/><inertia '
                  f'ixx="0.03" iyy="0.02" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>'
                  f'{geoms}</link>',
                  joint(f'j{index}', 'base', f'l{index}', extra=origin.replace('0.', '1.'))]
    text = robot(*parts)
    model = compiled(load_urdf(text))
    expected = yourdfpy.URDF.load(io.StringIO(text), build_scene_graph=False,
                                  load_meshes=False).robot
    for urdf_joint in expected.joints:
        body = model.body(urdf_joint.child).id
        np.testing.assert_allclose(model.body_pos[body], urdf_joint.origin[:3, 3], atol=1e-12)
        np.testing.assert_allclose(rotation(model.body_quat[body]), urdf_joint.origin[:3, :3],
                                   atol=1e-12)
    for urdf_link in expected.links[1:]:
        body = model.body(urdf_link.name).id
        origin = urdf_link.inertial.origin
        np.testing.assert_allclose(model.body_ipos[body], origin[:3, 3], atol=1e-12)
        in_body = (rotation(model.body_iquat[body]) @ np.diag(model.body_inertia[body])
                   @ rotation(model.body_iquat[body]).T)
        np.testing.assert_allclose(
            in_body, origin[:3, :3] @ np.diag([0.03, 0.02, 0.01]) @ origin[:3, :3].T,
            atol=1e-12)
        for group, shapes in ((builder.VISUAL_GROUP, urdf_link.visuals),
                              (builder.COLLISION_GROUP, urdf_link.collisions)):
            geoms = body_geoms(model, urdf_link.name, group)
            assert len(geoms) == len(shapes) == 2
            for geom, shape in zip(geoms, shapes):
                np.testing.assert_allclose(model.geom_pos[geom], shape.origin[:3, 3],
                                           atol=1e-12)
                np.testing.assert_allclose(rotation(model.geom_quat[geom]),
                                           shape.origin[:3, :3], atol=1e-12)


def test_root_link_gets_a_free_joint():
    description = load_urdf(GEOMETRY_ROBOT)
    model = compiled(description)
    assert not description.anchored
    assert model.jnt_type[model.body_jntadr[model.body('base').id]] == mujoco.mjtJoint.mjJNT_FREE


def test_root_fixed_to_world_link_is_anchored():
    description = load_urdf(robot('<link name="world"/>', link('post'),
                                  joint('anchor', 'world', 'post', 'fixed',
                                        '<origin xyz="1 2 3"/>')))
    model = compiled(description)
    assert description.anchored and description.root_link == 'post'
    assert model.body_jntnum[model.body('post').id] == 0
    assert description.root_position == pytest.approx((1.0, 2.0, 3.0))


def test_full_inertia_tensor_in_a_rotated_inertial_frame():
    tensor = np.array([[0.03, 0.004, 0.001], [0.004, 0.02, -0.002], [0.001, -0.002, 0.025]])
    inertial = ('<inertial><origin xyz="0.1 0 0" rpy="0 0 0.7"/><mass value="2.5"/>'
                f'<inertia ixx="{tensor[0, 0]}" iyy="{tensor[1, 1]}" izz="{tensor[2, 2]}" '
                f'ixy="{tensor[0, 1]}" ixz="{tensor[0, 2]}" iyz="{tensor[1, 2]}"/></inertial>')
    model = compiled(load_urdf(robot(f'<link name="solid">{inertial}</link>')))
    body = model.body('solid').id
    assert model.body_mass[body] == pytest.approx(2.5)
    np.testing.assert_allclose(model.body_ipos[body], [0.1, 0.0, 0.0])
    principal = np.zeros(9)
    mujoco.mju_quat2Mat(principal, model.body_iquat[body])
    principal = principal.reshape(3, 3)
    in_body = principal @ np.diag(model.body_inertia[body]) @ principal.T
    yaw = np.array([[math.cos(0.7), -math.sin(0.7), 0], [math.sin(0.7), math.cos(0.7), 0],
                    [0, 0, 1]])
    np.testing.assert_allclose(in_body, yaw @ tensor @ yaw.T, atol=1e-12)


ROS2_DIFF_DRIVE = """
<gazebo>
  <plugin name="drive" filename="libgazebo_ros_diff_drive.so">
    <ros><namespace>/bot</namespace><remapping>cmd_vel:=cmd</remapping></ros>
    <left_joint>left</left_joint>
    <right_joint>right</right_joint>
    <wheel_separation>0.3</wheel_separation>
    <wheel_diameter>0.1</wheel_diameter>
    <max_wheel_torque>2</max_wheel_torque>
    <max_wheel_acceleration>0.5</max_wheel_acceleration>
    <odometry_frame>odom_a</odometry_frame>
    <robot_base_frame>chassis</robot_base_frame>
    <odometry_source>0</odometry_source>
  </plugin>
</gazebo>
"""

ROS1_DIFF_DRIVE = """
<gazebo>
  <plugin name="drive" filename="libgazebo_ros_diff_drive.so">
    {legacy}
    <leftJoint>left</leftJoint>
    <rightJoint>right</rightJoint>
    <wheelSeparation>0.4</wheelSeparation>
    <wheelDiameter>0.12</wheelDiameter>
    <wheelTorque>3</wheelTorque>
    <wheelAcceleration>1.5</wheelAcceleration>
    <odometryFrame>odom_b</odometryFrame>
    <robotBaseFrame>base_b</robotBaseFrame>
    <odometrySource>world</odometrySource>
    <commandTopic>base/cmd_vel</commandTopic>
  </plugin>
</gazebo>
"""


def wheeled_robot(*extra):
    wheel = '<axis xyz="0 1 0"/>'
    return robot(link('chassis'), link('left_wheel', mass='0.2'), link('right_wheel', mass='0.2'),
                 joint('left', 'chassis', 'left_wheel', 'continuous', wheel),
                 joint('right', 'chassis', 'right_wheel', 'continuous', wheel), *extra)


def test_ros2_diff_drive_plugin():
    description = load_urdf(wheeled_robot(ROS2_DIFF_DRIVE))
    drive = description.diff_drive
    assert (drive.left_joints, drive.right_joints) == (('left',), ('right',))
    assert drive.wheel_separation == 0.3 and drive.wheel_diameter == 0.1
    assert drive.max_wheel_torque == 2.0 and drive.max_wheel_acceleration == 0.5
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom_a', 'chassis')
    assert drive.odometry_source == ODOMETRY_SOURCE_ENCODER
    (setup,) = description.plugins
    assert setup.block.ros_namespace == '/bot' and setup.block.ros_remappings == ('cmd_vel:=cmd',)
    model = compiled(description)
    for name in ('left', 'right'):
        actuator = model.actuator(diff_drive.drive_actuator_name(name))
        assert model.actuator_trnid[actuator.id][0] == model.joint(name).id
        np.testing.assert_allclose(model.actuator_forcerange[actuator.id], [-2.0, 2.0])
        assert model.actuator_dyntype[actuator.id] == mujoco.mjtDyn.mjDYN_INTEGRATOR


@pytest.mark.parametrize('legacy, swapped', [
    ('<legacyMode>false</legacyMode>', False), ('<legacyMode>true</legacyMode>', True),
    ('', False)])
def test_ros1_diff_drive_plugin(legacy, swapped):
    description = load_urdf(wheeled_robot(ROS1_DIFF_DRIVE.format(legacy=legacy)))
    drive = description.diff_drive
    # gazebo_ros in ROS 1 drove each wheel with the other side's speed in legacy mode, which
    # Melodic removed: without the tag the wheels are not swapped.
    expected = (('right',), ('left',)) if swapped else (('left',), ('right',))
    assert (drive.left_joints, drive.right_joints) == expected
    assert drive.legacy_mode is swapped
    assert drive.wheel_separation == 0.4 and drive.wheel_diameter == 0.12
    assert drive.max_wheel_torque == 3.0 and drive.max_wheel_acceleration == 1.5
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom_b', 'base_b')
    assert drive.odometry_source == ODOMETRY_SOURCE_WORLD
    assert drive_config.parameter(description.plugins[0].block, 'command_topic') == 'base/cmd_vel'


def test_diff_drive_defaults_follow_gazebo_ros():
    plugin = ('<gazebo><plugin name="d" filename="libgazebo_ros_diff_drive.so">'
              '<left_joint>left</left_joint><right_joint>right</right_joint></plugin></gazebo>')
    drive = load_urdf(wheeled_robot(plugin)).diff_drive
    assert drive.odometry_source == ODOMETRY_SOURCE_WORLD
    assert drive.max_wheel_acceleration == 0.0 and drive.max_wheel_torque == 5.0
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom', 'base_footprint')
    assert (drive.wheel_separation, drive.wheel_diameter) == (0.34, 0.15)
    # ROS 2's gazebo_ros publishes no odometry unless told to.
    assert not drive.publish_odom and not drive.publish_odom_tf


def test_robot_without_plugin_has_no_diff_drive():
    assert load_urdf(wheeled_robot()).diff_drive is None


def test_gazebo_friction_blocks():
    ball = '<collision><geometry><sphere radius="0.05"/></geometry></collision>'
    xml = robot(link('chassis'), link('tyre', ball), link('caster', ball),
                joint('axle', 'chassis', 'tyre', 'continuous'),
                joint('mount', 'chassis', 'caster'),
                '<gazebo reference="tyre"><mu1>0.8</mu1><mu2>0.6</mu2></gazebo>'
                '<gazebo reference="caster"><mu1>0</mu1><mu2>0</mu2></gazebo>')
    model = compiled(load_urdf(xml))
    (grippy,) = body_geoms(model, 'tyre', builder.COLLISION_GROUP)
    (slippery,) = body_geoms(model, 'caster', builder.COLLISION_GROUP)
    assert model.geom_friction[grippy][0] == pytest.approx(0.6)
    assert model.geom_priority[grippy] == 1 and model.geom_condim[grippy] == 3
    assert model.geom_friction[slippery][0] == 0.0
    assert model.geom_priority[slippery] == 1 and model.geom_condim[slippery] == 1


def write_mesh(path):
    with open(path, 'w') as mesh_file:
        mesh_file.write('v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\n'
                        'f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n')


def mesh_robot(filename):
    return robot(link('base', f'<visual><geometry><mesh filename="{filename}" scale="2 2 2"/>'
                              '</geometry></visual>'))


def test_relative_mesh_under_base_dir(tmp_path):
    (tmp_path / 'meshes').mkdir()
    write_mesh(tmp_path / 'meshes' / 'tetra.obj')
    description = load_urdf(mesh_robot('meshes/tetra.obj'), base_dir=str(tmp_path))
    model = compiled(description)
    assert model.nmesh == 1
    assert description.mesh_files == (str(tmp_path / 'meshes' / 'tetra.obj'),)
    (geom,) = body_geoms(model, 'base', builder.VISUAL_GROUP)
    assert model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_MESH


def test_package_and_file_uris_resolve_inside_the_share(tmp_path):
    share = tmp_path / 'share' / 'my_robot'
    (share / 'meshes').mkdir(parents=True)
    write_mesh(share / 'meshes' / 'tetra.obj')
    shares = {'my_robot': str(share)}
    for uri in ('package://my_robot/meshes/tetra.obj', f'file://{share}/meshes/tetra.obj'):
        description = load_urdf(mesh_robot(uri), package_resolver=shares.__getitem__)
        assert compiled(description).nmesh == 1


@pytest.mark.parametrize('filename, message', [
    ('../outside.obj', 'outside the model'),
    ('meshes/../../outside.obj', 'outside the model'),
    ('/etc/passwd', 'outside the model'),
    ('file:///etc/hosts', 'outside the model'),
    ('package://my_robot/../../outside.obj', 'outside the model'),
    ('http://example.com/m.obj', 'unsupported URI scheme'),
    ('meshes/body.ply', 'unsupported format'),
])
def test_mesh_paths_that_are_refused(tmp_path, filename, message):
    model_dir = tmp_path / 'share' / 'my_robot'
    (model_dir / 'meshes').mkdir(parents=True)
    write_mesh(tmp_path / 'outside.obj')
    shares = {'my_robot': str(model_dir)}
    with pytest.raises(UrdfError, match=message.replace('(', r'\(').replace(')', r'\)')):
        load_urdf(mesh_robot(filename), base_dir=str(model_dir),
                  package_resolver=shares.__getitem__)


@pytest.mark.parametrize('scale, message', [
    ('1e20', "link 'base' mesh 'tetra.obj' scaled by [1e+20, 1e+20, 1e+20] is 1e+19 m across, "
     'more than the limit of 1000 m'),
    ('1 1 1e5', "link 'base' mesh 'tetra.obj' scaled by [1.0, 1.0, 100000.0] is 10000 m "
     'across, more than the limit of 1000 m'),
    ('1 0 1', "link 'base' mesh scale must be finite and non-zero: [1.0, 0.0, 1.0]"),
])
def test_a_mesh_scaled_beyond_the_worlds_reach_is_refused(tmp_path, scale, message):
    write_mesh(tmp_path / 'tetra.obj')
    urdf = robot(link('base', f'<collision><geometry><mesh filename="tetra.obj" '
                              f'scale="{scale}"/></geometry></collision>'))
    with pytest.raises(UrdfError) as refusal:
        load_urdf(urdf, base_dir=str(tmp_path))
    assert str(refusal.value) == message


def test_a_mirrored_mesh_less_than_a_kilometre_across_is_taken(tmp_path):
    write_mesh(tmp_path / 'tetra.obj')
    urdf = robot(link('base', '<collision><geometry><mesh filename="tetra.obj" '
                              'scale="-9000 9000 9000"/></geometry></collision>'))
    assert compiled(load_urdf(urdf, base_dir=str(tmp_path))).nmesh == 1


@pytest.mark.parametrize('filename, reason', [
    ('package://unknown_pkg/m.obj', "package 'unknown_pkg' is not found"),
    ('meshes/missing.obj', 'no such file'),
    ('meshes/body.dae', 'no such file'),
])
def test_meshes_that_cannot_be_had_are_left_out(tmp_path, filename, reason):
    model_dir = tmp_path / 'share' / 'my_robot'
    (model_dir / 'meshes').mkdir(parents=True)
    shares = {'my_robot': str(model_dir)}
    description = load_urdf(mesh_robot(filename), base_dir=str(model_dir),
                            package_resolver=shares.__getitem__)
    assert description.missing_meshes == (filename,)
    assert description.notes == (f"mesh '{filename}' cannot be had, so it is left out: "
                                 f'{reason}',)
    assert compiled(description).ngeom == 0


def test_symlink_out_of_the_model_folder_is_refused(tmp_path):
    model_dir = tmp_path / 'model'
    model_dir.mkdir()
    write_mesh(tmp_path / 'secret.obj')
    os.symlink(tmp_path / 'secret.obj', model_dir / 'innocent.obj')
    with pytest.raises(UrdfError, match='outside the model'):
        load_urdf(mesh_robot('innocent.obj'), base_dir=str(model_dir))


def test_external_entity_is_refused_without_reading_the_file(tmp_path):
    secret = tmp_path / 'secret.txt'
    secret.write_text('TOP-SECRET-CONTENT')
    xml = (f'<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY leak SYSTEM "file://{secret}">]>'
           '<robot name="&leak;"><link name="a"/></robot>')
    with pytest.raises(UrdfError) as refused:
        load_urdf(xml)
    assert 'DOCTYPE' in str(refused.value)
    assert 'TOP-SECRET' not in str(refused.value)


def test_external_doctype_is_refused(tmp_path):
    secret = tmp_path / 'secret.dtd'
    secret.write_text('<!ENTITY leak "TOP-SECRET">')
    xml = f'<!DOCTYPE robot SYSTEM "file://{secret}"><robot name="r"><link name="a"/></robot>'
    with pytest.raises(UrdfError, match='DOCTYPE'):
        load_urdf(xml)


def test_entity_expansion_bomb_is_refused():
    entities = '<!ENTITY a0 "lol">' + ''.join(
        f'<!ENTITY a{i} "{f"&a{i - 1};" * 10}">' for i in range(1, 10))
    xml = f'<!DOCTYPE robot [{entities}]><robot name="&a9;"><link name="a"/></robot>'
    with pytest.raises(UrdfError, match='DOCTYPE'):
        load_urdf(xml)


def test_oversized_model_xml_is_refused_before_parsing():
    padding = '<!--' + 'x' * hardened_xml.MAX_MODEL_XML_BYTES + '-->'
    with pytest.raises(UrdfError, match='more than the limit'):
        load_urdf(robot(link('a'), padding))


NAN_ORIGIN = '<origin xyz="0 nan 0"/>'


@pytest.mark.parametrize('xml, message', [
    ('', 'model_xml is empty'),
    ('<robot name="r"><link name="a"></robot>', 'does not parse as XML'),
    ('<sdf version="1.6"><model name="m"/></sdf>',
     r'model_xml is not URDF: root element is <sdf>'),
    ('<robot name="r"/>', r'has no <link>'),
    ('<robot><link name="a"/></robot>', 'has no name attribute'),
    ('<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">'
     '<xacro:property name="w" value="1"/><link name="a"/></robot>', 'run xacro'),
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'floating')),
     "type 'floating', which is not supported"),
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'planar')),
     "type 'planar', which is not supported"),
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'hinge')),
     "joint 'j' has unknown type 'hinge'"),
    (robot(link('a', '<visual><geometry><box size="1 1 1"/></geometry><material name="m">'
                     '<color rgba="1 0 nan 1"/></material></visual>')),
     r"link 'a' <color rgba> contains NaN or infinity"),
    ('<robot name="r"><link name="a"/></robot>'.encode('utf-16'), 'must be UTF-8'),
    (robot(link('a'), link('b'), joint('j', 'a', 'ghost')), "names missing link 'ghost'"),
    (robot(link('a'), link('b'), joint('j1', 'a', 'b'), joint('j2', 'b', 'a')),
     'joints form a loop'),
    (robot(link('root'), link('a'), link('b'), joint('j1', 'a', 'b'), joint('j2', 'b', 'a')),
     'joints form a loop'),
    (robot(link('a'), link('b')), 'more than one root link'),
    (robot(link('a'), link('a')), "link 'a' is defined twice"),
    (robot(link('a', mass='0')), 'mass must be positive'),
    (robot(link('a', mass='-2')), 'mass must be positive'),
    (robot(link('a', mass='nan')), 'contains NaN or infinity'),
    (robot('<link name="a"><inertial><mass value="1"/><inertia ixx="1" iyy="-1" izz="1" '
           'ixy="0" ixz="0" iyz="0"/></inertial></link>'), 'not positive definite'),
    (robot('<link name="a"><inertial><mass value="1"/><inertia ixx="nan" iyy="1" izz="1" '
           'ixy="0" ixz="0" iyz="0"/></inertial></link>'), 'contains NaN or infinity'),
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'fixed', NAN_ORIGIN)),
     r"joint 'j' <origin xyz> contains NaN or infinity"),
    (robot(link('a', f'<visual>{NAN_ORIGIN}<geometry><sphere radius="1"/></geometry></visual>')),
     r"link 'a' <origin xyz> contains NaN or infinity"),
    (robot(link('a', '<visual><geometry><box size="1 0 1"/></geometry></visual>')),
     'must be 3 positive numbers'),
    (robot(link('a', '<visual><geometry><box size="1 2000 1"/></geometry></visual>')),
     re.escape("link 'a' box size [1.0, 2000.0, 1.0]: the shape is 2000 m across, more than "
               'the limit of 1000 m')),
    (robot(link('a', '<collision><geometry><cylinder radius="501" length="1"/></geometry>'
                     '</collision>')),
     re.escape("link 'a' cylinder radius and length [501.0, 1.0]: the shape is 1002 m "
               'across, more than the limit of 1000 m')),
    (robot(link('a', '<collision><geometry><cylinder radius="1" length="1e300"/></geometry>'
                     '</collision>')),
     re.escape("link 'a' cylinder radius and length [1.0, 1e+300]: the shape is 1e+300 m "
               'across')),
    (robot(link('a', '<visual><geometry><sphere radius="1e6"/></geometry></visual>')),
     re.escape("link 'a' sphere radius [1000000.0]: the shape is 2e+06 m across")),
    (robot(link('a', '<visual><geometry><sphere radius="-1"/></geometry></visual>')),
     re.escape("link 'a' sphere radius must be 1 positive numbers: [-1.0]")),
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'revolute',
                                       '<limit lower="1" upper="-1" effort="1" velocity="1"/>')),
     'is not below upper'),
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'continuous', '<axis xyz="0 0 0"/>')),
     "joint 'j' axis is zero"),
    (wheeled_robot('<gazebo><plugin name="d" filename="libgazebo_ros_diff_drive.so">'
                   '<left_joint>left</left_joint><right_joint>nope</right_joint>'
                   '</plugin></gazebo>'), "wheel joint 'nope' is not a joint"),
    (wheeled_robot('<gazebo><plugin name="d" filename="libgazebo_ros_diff_drive.so">'
                   '<left_joint>left</left_joint><right_joint>right</right_joint>'
                   '<wheel_diameter>-1</wheel_diameter></plugin></gazebo>'),
     'wheel_diameter> must be one number > 0'),
])
def test_refused_urdf(xml, message):
    with pytest.raises(UrdfError, match=message):
        load_urdf(xml)


def test_refusals_reach_the_world_as_world_errors():
    world = World()
    with pytest.raises(WorldError, match=r'model_xml is not URDF: root element is <sdf>'):
        spawn_robot(world, 'thing', '<sdf version="1.6"/>')
    with pytest.raises(WorldError, match='DOCTYPE'):
        spawn_robot(world, 'thing', '<!DOCTYPE robot SYSTEM "file:///etc/passwd"><robot/>')
    with pytest.raises(WorldError, match='outside the model'):
        spawn_robot(world, 'thing', mesh_robot('/etc/passwd'), base_dir='/tmp')
    assert world.model_names() == []
    assert world.model.nbody == 1


def test_mesh_robot_can_be_deleted_and_spawned_again(tmp_path):
    write_mesh(tmp_path / 'tetra.obj')
    with open(tmp_path / 'flat.obj', 'w') as mesh_file:
        mesh_file.write('v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n')
    urdf = robot(link('base', '<visual><geometry><mesh filename="flat.obj"/></geometry></visual>'
                              '<collision><geometry><mesh filename="tetra.obj"/></geometry>'
                              '</collision>'))
    world = World()
    for _ in range(2):
        spawn_robot(world, 'meshy', urdf, base_dir=str(tmp_path))
        assert world.model.nmesh == 2
        world.delete_model('meshy')
        assert world.model.nmesh == 0


@pytest.mark.parametrize('xml, message', [
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'fixed', '<origin xyz="0 1"/>')),
     r"joint 'j' <origin xyz> must hold 3 numbers, not 2: '0 1'"),
    (robot(link('a', '<visual><geometry><box size="1 1 1 1"/></geometry></visual>')),
     r"link 'a' <box size> must hold 3 numbers, not 4: '1 1 1 1'"),
    (robot(link('a', '<visual><geometry><mesh filename="m.obj" scale="1 2"/></geometry>'
                     '</visual>')),
     r"link 'a' <mesh scale> must hold 1 or 3 numbers, not 2: '1 2'"),
    (robot(link('a', mass='1 2')), r"link 'a' <mass value> must hold 1 numbers, not 2"),
    (robot(link('a'), link('b'), joint('j', 'a', 'b', 'fixed', f'<origin xyz="{"9" * 400}"/>')),
     r"joint 'j' <origin xyz> contains NaN or infinity: '9{80}\.\.\.'"),
])
def test_numbers_of_the_wrong_count_or_size_are_refused_by_name(xml, message):
    with pytest.raises(UrdfError, match=message):
        load_urdf(xml)
