"""Per-link <gazebo reference> settings, and the plugins the world does not stand in for."""

import logging
import math

import numpy as np
import pytest
from repository import model_path, read_model, TEST_MODELS
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.urdf import builder
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot

LINKBOT = model_path('linkbot', TEST_MODELS)
LINKBOT_MASS = 2.0 + 0.2 + 0.01 + 0.05
INERTIAL = ('<inertial><mass value="{mass}"/><inertia ixx="0.01" iyy="0.01" izz="0.01" '
            'ixy="0" ixz="0" iyz="0"/></inertial>')


def read_linkbot():
    return read_model('linkbot', TEST_MODELS)


def geoms(mj_model, body_name, group):
    body = mj_model.body(body_name).id
    return [geom for geom in range(mj_model.ngeom)
            if mj_model.geom_bodyid[geom] == body and mj_model.geom_group[geom] == group]


def test_gazebo_materials_colour_the_links_visuals():
    description = load_urdf(read_linkbot())
    mj_model = description.spec.compile()
    colours = {link: mj_model.geom_rgba[geoms(mj_model, link, builder.VISUAL_GROUP)[0]]
               for link in ('base_link', 'mast', 'flag', 'balloon')}
    # Gazebo's material wins over the URDF's own colour (white here).
    np.testing.assert_allclose(colours['base_link'], [1.0, 0.0, 0.0, 1.0])
    # Gazebo/Gray is not a Gazebo material; it is taken as Gazebo/Grey.
    np.testing.assert_allclose(colours['mast'], [0.7, 0.7, 0.7, 1.0])
    np.testing.assert_allclose(colours['balloon'], [0.13, 0.44, 0.70, 1.0])
    # A name Gazebo does not know keeps the URDF colour, and is noted.
    np.testing.assert_allclose(colours['flag'], [0.0, 0.6, 0.0, 1.0])
    assert ("link 'flag' material 'Custom/Flag' is not one of Gazebo's flat colours; the URDF "
            'colour is kept') in description.notes


def test_kp_and_kd_set_the_contact_softness_of_their_link_only():
    mj_model = load_urdf(read_linkbot()).spec.compile()
    (base,) = geoms(mj_model, 'base_link', builder.COLLISION_GROUP)
    (balloon,) = geoms(mj_model, 'balloon', builder.COLLISION_GROUP)
    # kp 1e6 N/m under the robot's weight: a mass-spring of 2 pi sqrt(m / kp) seconds; kd 100
    # N s/m damps it less than critically, which ODE's implicit step does not: ratio 1.
    np.testing.assert_allclose(mj_model.geom_solref[base],
                               [2.0 * math.pi * math.sqrt(LINKBOT_MASS / 1e6), 1.0])
    np.testing.assert_allclose(mj_model.geom_solref[balloon], [builder.CONTACT_TIME_CONSTANT, 1.0])
    assert mj_model.geom_friction[base][0] == pytest.approx(0.8)


def box_robot(gazebo_tags, mass='1'):
    return (f'<robot name="r"><link name="a">{INERTIAL.format(mass=mass)}<collision><geometry>'
            '<box size="0.1 0.1 0.1"/></geometry></collision></link>'
            f'<gazebo reference="a">{gazebo_tags}</gazebo></robot>')


@pytest.mark.parametrize('tags, timestep, solref', [
    # Rigid, as Gazebo's default kp: no faster than two timesteps.
    ('<kp>1e12</kp>', 0.002, [0.004, 1.0]),
    ('<kp>1e12</kp>', 0.001, [0.002, 1.0]),
    # Soft, and damped more than critically.
    ('<kp>100</kp><kd>1000</kd>', 0.002, [2.0 * math.pi * math.sqrt(4.0 / 100.0),
                                          1000.0 / (2.0 * math.sqrt(100.0 * 4.0))]),
    # kd alone leaves the world's contact, which kp's default keeps rigid.
    ('<kd>5</kd>', 0.002, [builder.CONTACT_TIME_CONSTANT, 1.0]),
])
def test_contact_stiffness_is_never_faster_than_two_timesteps(tags, timestep, solref):
    mj_model = load_urdf(box_robot(tags, mass='4'), timestep=timestep).spec.compile()
    np.testing.assert_allclose(mj_model.geom_solref[0], solref)


def flaps(left, right):
    """Return a base with two flaps on hinges whose boxes overlap, with their selfCollide."""
    def flap(name, x, self_collide):
        return (f'<link name="{name}">{INERTIAL.format(mass=0.1)}<collision><geometry>'
                '<box size="0.1 0.1 0.02"/></geometry></collision></link>'
                f'<joint name="{name}_hinge" type="continuous"><parent link="base"/>'
                f'<child link="{name}"/><origin xyz="{x} 0 0.2"/><axis xyz="0 1 0"/></joint>'
                f'<gazebo reference="{name}"><selfCollide>{self_collide}</selfCollide></gazebo>')
    return (f'<robot name="flaps"><link name="base">{INERTIAL.format(mass=5)}<collision>'
            '<geometry><box size="0.3 0.3 0.1"/></geometry></collision></link>'
            f'{flap("left", 0.0, left)}{flap("right", 0.05, right)}</robot>')


@pytest.mark.parametrize('left, right, collide', [
    ('false', 'false', False), ('true', 'false', False), ('true', 'true', True)])
def test_links_of_one_robot_collide_only_if_both_say_self_collide(left, right, collide):
    world = World()
    spawn_robot(world, 'flaps', flaps(left, right), position=(0.0, 0.0, 0.05))
    world.step(1)
    mj_model, data = world.model, world.data
    pairs = {frozenset(mj_model.body(mj_model.geom_bodyid[geom]).name
                       for geom in (contact.geom1, contact.geom2))
             for contact in data.contact[:data.ncon]}
    assert (frozenset({'flaps::left', 'flaps::right'}) in pairs) is collide


def knot(anchored, self_collide='false'):
    """
    Return a robot of six links whose boxes all overlap.

    The plate is fixed to the base, the arm hinged to it, the hand fixed to the arm, the
    finger hinged to the hand, and the thumb hinged to the base.
    """
    joints = (('plate', 'base', 'fixed'), ('arm', 'base', 'continuous'),
              ('hand', 'arm', 'fixed'), ('finger', 'hand', 'continuous'),
              ('thumb', 'base', 'continuous'))
    links = ''.join(f'<link name="{name}">{INERTIAL.format(mass=0.5)}<collision><geometry>'
                    '<box size="0.2 0.2 0.2"/></geometry></collision></link>'
                    f'<gazebo reference="{name}"><selfCollide>{self_collide}</selfCollide>'
                    '</gazebo>' for name in ('base', *(child for child, _, _ in joints)))
    links += ''.join(f'<joint name="{child}_joint" type="{kind}"><parent link="{parent}"/>'
                     f'<child link="{child}"/><axis xyz="0 0 1"/></joint>'
                     for child, parent, kind in joints)
    if anchored:
        links += ('<link name="world"/><joint name="anchor" type="fixed"><parent link="world"/>'
                  '<child link="base"/><origin xyz="0 0 0.5"/></joint>')
    return f'<robot name="knot">{links}</robot>'


def touching_links(world, name):
    """Return the pairs of a robot's own links in contact, by link name."""
    mj_model, data = world.model, world.data
    prefix = name + '::'
    pairs = (tuple(mj_model.body(mj_model.geom_bodyid[geom]).name
                   for geom in (contact.geom1, contact.geom2))
             for contact in data.contact[:data.ncon])
    return {frozenset(body[len(prefix):] for body in pair) for pair in pairs
            if all(body.startswith(prefix) for body in pair)}


@pytest.mark.parametrize('anchored, excludes', [(False, 5), (True, 11)])
def test_overlapping_links_of_one_robot_never_touch_however_they_are_joined(anchored,
                                                                            excludes):
    world = World()
    spawn_robot(world, 'knot', knot(anchored), position=(0.0, 0.0, 0.3))
    world.step(1)
    assert touching_links(world, 'knot') == set()
    # MuJoCo keeps apart links fixed to each other and a joint's two sides itself (not when
    # one side is fixed to the world): only the other pairs of the 15 need an exclude.
    assert world.model.nexclude == excludes
    # The same links, told to collide, touch wherever MuJoCo does not keep them apart.
    spawn_robot(world, 'loose', knot(anchored, 'true'), position=(2.0, 0.0, 0.3))
    world.step(1)
    touching = touching_links(world, 'loose')
    assert {frozenset({'arm', 'thumb'}), frozenset({'finger', 'base'})} <= touching


def test_a_link_without_gravity_floats_and_one_with_it_falls():
    for gravity, angle in (('false', 0.0), ('true', -math.pi / 2.0)):
        world = World()
        spawn_robot(world, 'linkbot', read_linkbot().replace('<gravity>false</gravity>',
                                                             f'<gravity>{gravity}</gravity>'))
        world.step(2000)
        _, positions, _ = world.joint_state('linkbot')
        # Held out along +y on a hinge about x, the balloon hangs straight down if it weighs.
        assert positions[0] == pytest.approx(angle, abs=0.05)


def test_turn_gravity_off_is_the_old_spelling_of_gravity_false():
    mj_model = load_urdf(box_robot('<turnGravityOff>true</turnGravityOff>')).spec.compile()
    assert mj_model.body_gravcomp[mj_model.body('a').id] == 1.0


@pytest.mark.parametrize('tags, message', [
    ('<kp>nan</kp>', "gazebo <kp> of link 'a' contains NaN or infinity: 'nan'"),
    ('<kp>-1</kp>', "gazebo <kp> of link 'a' must be one number > 0: '-1'"),
    ('<kp>0</kp>', "gazebo <kp> of link 'a' must be one number > 0: '0'"),
    ('<kd>-5</kd>', "gazebo <kd> of link 'a' must be one number >= 0: '-5'"),
    ('<mu1>inf</mu1>', "gazebo <mu1> of link 'a' contains NaN or infinity: 'inf'"),
    ('<mu2>-0.5</mu2>', "gazebo <mu2> of link 'a' must be one number >= 0: '-0.5'"),
    ('<selfCollide>maybe</selfCollide>',
     "gazebo <selfCollide> of link 'a' must be true or false: 'maybe'"),
    ('<gravity>2</gravity>', "gazebo <gravity> of link 'a' must be true or false: '2'"),
])
def test_bad_link_settings_are_refused_by_link_tag_and_value(tags, message):
    with pytest.raises(UrdfError, match=message):
        load_urdf(box_robot(tags))


def test_plugins_not_simulated_here_are_named_once_in_order_and_logged_once(caplog):
    world = World()
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        model = spawn_file(world, 'linkbot', LINKBOT)
        world.step(100)
        world.reset_world()
    assert model is world.models['linkbot']
    # The bumper's plugin sits in a <sensor> of a <gazebo reference> block; p3d comes twice.
    assert model.description.ignored_plugins == ('libgazebo_ros_bumper.so',
                                                 'libgazebo_ros_p3d.so')
    logged = [record.getMessage() for record in caplog.records]
    assert logged == [f"model 'linkbot': {note}" for note in model.description.notes]
    assert logged.count("model 'linkbot': plugin 'libgazebo_ros_p3d.so' is not simulated "
                        'here; it is ignored') == 1
