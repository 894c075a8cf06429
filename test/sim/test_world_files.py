"""World files read without ROS, and a World loading another scenery in place of its own."""

import math
import os

import mujoco
import pytest
from repository import read_model, ROOT
from service_tutorial.sim.scenery import Scenery, SceneryError
from service_tutorial.sim.validation import Reason
from service_tutorial.sim.world import World
from service_tutorial.sim.world_files import parse_world, read_world_file, WorldFileError
from service_tutorial.testing.spawns import spawn_robot

PARSE, MISSING, FORMAT = Reason.NOT_PARSEABLE, Reason.NO_RESOURCE, Reason.UNSUPPORTED_FORMAT


def own_share(package):
    """Resolve this package to the repository, which holds worlds/ and models/ as installed."""
    if package != 'service_tutorial':
        raise LookupError(package)
    return ROOT


def world_file(name):
    """Read one of the package's world files."""
    return read_world_file(os.path.join(ROOT, 'worlds', name + '.world.xml'), own_share)


def test_the_yard_names_the_lessons_poses_and_starts_tinybot_at_its_start():
    yard = world_file('yard')
    assert yard.name == 'yard' and 'default' in yard.tags
    assert yard.scenery == os.path.realpath(os.path.join(ROOT, 'models', 'yard.urdf'))
    tinybot, = yard.models
    assert (tinybot.name, tinybot.position) == ('tinybot', (0.0, 0.0, 0.0))
    r2d2 = yard.named_poses['r2d2_spawn']
    assert r2d2.position == (-2.0, 1.0, 1.0)
    # -90 degrees about z, as the lesson's spawn_model_client turns R2-D2 (w, x, y, z).
    assert all(math.isclose(a, b, abs_tol=1e-9) for a, b in zip(
        r2d2.orientation, (math.sqrt(0.5), 0.0, 0.0, -math.sqrt(0.5))))
    assert (r2d2.bounds_type, r2d2.bounds_points) == ('sphere', ((-2.0, 1.0, 1.0),
                                                                 (0.8, 0.0, 0.0)))


def test_the_parking_spot_lies_in_front_of_the_crate_and_inside_its_bounds():
    parking = world_file('parking')
    spot = parking.named_poses['parking_spot']
    (low, high) = spot.bounds_points
    assert all(a <= p <= b for a, p, b in zip(low, spot.position, high))
    crate_face = 2.4  # the crate's near face, worlds/parking.xml
    assert high[0] < crate_face and spot.position[0] < crate_face
    assert world_file('empty').scenery == '' and world_file('empty').models == ()


@pytest.mark.parametrize('text, kind, named', [
    ('<gazebo/>', FORMAT, '<gazebo>'),
    ('<sdf/>', PARSE, "version '', not X.Y"),
    ('<world name=" "/>', PARSE, 'world name'),
    ('<world><named_pose name="a"/><named_pose name="a"/></world>', PARSE, 'twice'),
    ('<world><model uri="package://service_tutorial/models/tinybot.urdf" pose="b"/></world>',
     PARSE, "pose 'b'"),
    ('<world><named_pose name="a"><bounds type="box" min="0 0 0" max="1 0 1"/></named_pose>'
     '</world>', PARSE, 'below max'),
    ('<world><named_pose name="a"><origin xyz="nan 0 0"/></named_pose></world>', PARSE,
     'NaN'),
    ('<world><named_pose name="a"><origin xyz="1e9 0 0"/></named_pose></world>', PARSE,
     'beyond'),
    ('<world><named_pose name="a"><bounds type="cone"/></named_pose></world>', PARSE,
     'box or sphere'),
    ('<world><scenery uri="package://service_tutorial/../etc/passwd"/></world>', MISSING,
     "'..'"),
    ('<world><scenery uri="yard.urdf"/></world>', MISSING, 'neither'),
    ('<world><model uri="package://service_tutorial/models/none.urdf"/></world>', MISSING,
     'names no file'),
    ('<world>' + '<tag>t</tag>' * 5000 + '</world>', PARSE, 'more than'),
    ('<world><tag>' + 'x' * 300 + '</tag></world>', PARSE, 'tag'),
])
def test_a_bad_world_is_refused_with_what_is_wrong(text, kind, named):
    with pytest.raises(WorldFileError) as refused:
        parse_world(text, 'the world', None, own_share)
    assert refused.value.reason == kind and named in str(refused.value)


def test_unknown_elements_are_listed_for_the_loader_to_judge():
    world = parse_world('<world name="w"><light/><named_pose name="p"><colour/></named_pose>'
                        '</world>', 'w', None, own_share)
    assert world.unsupported == ('<light>', '<colour> in <named_pose>')


def test_a_scenery_given_as_text_names_no_file():
    with pytest.raises(SceneryError, match='outside'):
        Scenery.from_text('<mujoco><asset><mesh file="/etc/hostname"/></asset></mujoco>', 'text')
    hinged = ('<mujoco><worldbody><body><joint type="hinge"/><geom size="0.1"/></body>'
              '</worldbody></mujoco>')
    with pytest.raises(SceneryError) as refused:
        Scenery.from_text(hinged, 'text')
    assert refused.value.reason == Reason.UNSUPPORTED_CONTENT


def test_a_world_loads_another_scenery_without_its_models_at_time_zero():
    world = World(scenery=os.path.join(ROOT, 'models', 'yard.urdf'))
    spawn_robot(world, 'tinybot', read_model('tinybot'))
    world.step(100)
    parking = Scenery(os.path.join(ROOT, 'worlds', 'parking.xml'))
    world.load(parking)
    assert world.model_names() == [] and world.time == 0.0
    geoms = {mujoco.mj_id2name(world.model, mujoco.mjtObj.mjOBJ_GEOM, index)
             for index in range(world.model.ngeom)}
    assert {'scenery/wall', 'scenery/crate'} <= geoms
    # The tinybot spawned into the parking world stands at rest before the crate.
    spawn_robot(world, 'tinybot', read_model('tinybot'))
    world.step(250)
    assert abs(world.get_model_state('tinybot').linear_velocity[0]) < 1e-3
    world.load(None)
    assert world.model.ngeom == 1  # the ground alone
