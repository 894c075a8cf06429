"""Scenery: static obstacles from a URDF or MJCF file, part of the scene and not a model."""

import math

import numpy as np
import pytest
from repository import model_path, R2D2, TEST_MODELS, TINYBOT
from service_tutorial.sim.plugins.ray_sensor import RaySensor
from service_tutorial.sim.validation import quoted, WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file

YARD = model_path('yard')
LASER_ROBOT = model_path('sensor_laser', TEST_MODELS)
# A box 1 m ahead of sensor_laser's beams, straight in the world body, and one on a body.
MJCF_BOXES = """<mujoco>
  <worldbody>
    <geom name="near" type="box" size="0.05 0.5 0.5" pos="1.1 0 0.5" rgba="0 1 0 1"/>
    <body name="far" pos="0 3 0"><geom type="box" size="0.2 0.2 0.2" pos="0 0 0.2"/></body>
  </worldbody>
</mujoco>"""


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def scan(world, name='laser'):
    """Return one scan of a model's laser."""
    laser = world.models[name].plugin(RaySensor)
    laser.set_active(True)
    world.step(1)
    laser.set_active(False)
    return laser.ranges.copy()


def test_the_yard_is_scenery_not_a_model_and_keeps_the_lesson_places_clear():
    world = World(scenery=YARD)
    assert world.model_names() == []
    # The floor, and a visual and a collision shape for 4 walls, 4 crates and a post.
    assert world.model.ngeom == 1 + 2 * 9
    # tinybot at the origin and R2-D2 at the lesson's spawn point fit in and stand there.
    spawn_file(world, 'tinybot', TINYBOT)
    spawn_file(world, 'r2d2', R2D2, position=(-2.0, 1.0, 1.0),
               orientation=(math.cos(-math.pi / 4), 0.0, 0.0, math.sin(-math.pi / 4)))
    world.step(round(2.0 / world.timestep))
    assert world.model_names() == ['tinybot', 'r2d2']
    assert world.get_model_state('tinybot').position == pytest.approx([0.0, 0.0, 0.0], abs=2e-3)
    assert world.get_model_state('r2d2').position[:2] == pytest.approx([-2.0, 1.0], abs=0.02)
    # Deleting a model rebuilds the scene: the yard stays.
    world.delete_model('r2d2')
    ranges = scan(world, 'tinybot')
    # tinybot's laser (1 degree a beam, from -180) sees the east wall's face at x = 5.
    assert ranges[180] == pytest.approx(5.0 - 0.02, abs=0.05)
    assert np.isfinite(ranges).all(), 'the walls close the yard all round'


def test_mjcf_scenery_geoms_of_the_world_body_and_of_bodies_are_seen(tmp_path):
    world = World(scenery=write(tmp_path, 'boxes.xml', MJCF_BOXES))
    spawn_file(world, 'laser', LASER_ROBOT)
    ranges = scan(world)
    assert ranges[90] == pytest.approx(1.0, abs=0.005)
    world.set_model_state('laser', position=(0.0, 3.0 - 0.5, 0.0),
                          orientation=(math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)))
    # Now facing +y, 0.5 m from the second box's centre: its face is 0.3 m away, less the
    # beam's 5 cm offset along the post's x (now the world's y).
    assert scan(world)[90] == pytest.approx(0.5 - 0.2 - 0.05, abs=0.005)
    assert world.model_names() == ['laser']


@pytest.mark.parametrize('name, text, message', [
    ('free.urdf', '<robot name="free"><link name="box"><collision><geometry>'
     '<box size="1 1 1"/></geometry></collision></link></robot>',
     "must fix its root link 'box' to the link 'world' with a fixed joint"),
    ('hinge.urdf', '<robot name="gate"><link name="world"/><link name="post"/>'
     '<link name="leaf"/><joint name="fix" type="fixed"><parent link="world"/>'
     '<child link="post"/></joint><joint name="hinge" type="continuous">'
     '<parent link="post"/><child link="leaf"/><axis xyz="0 0 1"/></joint></robot>',
     'has moving joints (hinge); scenery is static'),
    ('include.xml', '<mujoco><include file="/etc/passwd"/></mujoco>',
     'has an <include>, which scenery files may not have'),
    ('ball.xml', '<mujoco><worldbody><body><freejoint/><geom size="0.1"/></body></worldbody>'
     '</mujoco>', 'has joints (1); scenery is static'),
    ('typo.xml', '<mujoco><worldbody><geom type="blob"/></worldbody></mujoco>',
     'is not valid MJCF'),
    ('bad.xml', '<mujoco><worldbody><geom type="box" size="-1 1 1"/></worldbody></mujoco>',
     'does not compile: size 0 must be positive in geom'),
    ('entity.xml', '<!DOCTYPE m [<!ENTITY e SYSTEM "file:///etc/passwd">]><mujoco>&e;</mujoco>',
     'contains a DOCTYPE or ENTITY declaration, which is refused'),
    ('world.sdf', '<sdf version="1.6"><world name="w"/></sdf>',
     'is SDF (root element <sdf>)'),
])
def test_scenery_that_is_not_static_or_not_safe_is_refused(tmp_path, name, text, message):
    path = write(tmp_path, name, text)
    with pytest.raises(WorldError) as refusal:
        World(scenery=path)
    # Named whole, or cut as quoted() cuts user text when the path is long (pytest -n 2's are).
    names = (f"'{path}'", quoted(path))
    assert any(f'scenery file {named}' in str(refusal.value) for named in names)
    assert message in str(refusal.value)


def test_a_missing_scenery_file_is_refused_by_name(tmp_path):
    path = str(tmp_path / 'nowhere.urdf')
    with pytest.raises(WorldError, match=f"scenery file '{path}' cannot be read"):
        World(scenery=path)
