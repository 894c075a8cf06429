"""
One judgement of a robot file, and one reason for a refusal, whichever service is asked.

GetSpawnables reads a file with the reader and the loader a spawn by its uri uses: a file it
offers spawns, and a file SpawnEntity refuses is left out with the spawn's own words. A bad
request gets the same words through the lesson's /mujoco/spawn_urdf_model and the standard's
/spawn_entity, each dialect's own code or success flag around them, and the world judges it
once: spies on the core's checks count one call per request.
"""

import math

import pytest
from repository import install_package, MJCF_CRATE, read_file, read_model
from service_tutorial.sim import validation
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES
from service_tutorial.world_node import node
from simulation_interfaces.msg import Result, SpawnResult
from simulation_interfaces.srv import GetSpawnables, UnloadWorld
from standard_entities import snapshot, spawn, spawn_or_fail, stamped

pytestmark = pytest.mark.ros

CRATE = read_file(MJCF_CRATE)
TOO_HEAVY = ('<robot name="heavy"><link name="a"><inertial><mass value="1"/><inertia ixx="1" '
             'iyy="1" izz="3" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>')


@pytest.fixture
def world(ros):
    """Start the default world, tinybot at the origin, paused: nothing moves between calls."""
    return ros.start_world(paused=True, real_time_factor=0.0)


@pytest.fixture
def judged_package(tmp_path, monkeypatch):
    """Install a package whose mjcf/ and urdf/ hold a good robot and three bad ones."""
    share = install_package(tmp_path, monkeypatch, 'judged_pkg')
    (share / 'mjcf').mkdir()
    (share / 'urdf').mkdir()
    (share / 'mjcf' / 'crate.xml').write_text(CRATE)
    (share / 'mjcf' / 'part.xml').write_text('<mujoco><worldbody/></mujoco>')
    (share / 'mjcf' / 'including.xml').write_text(
        '<mujoco model="including"><include file="part.xml"/></mujoco>')
    (share / 'mjcf' / 'absent.xml').write_text(
        '<mujoco model="absent"><asset><mesh name="m" file="absent.obj"/></asset><worldbody>'
        '<body name="b"><freejoint/><geom type="mesh" mesh="m" mass="1"/></body></worldbody>'
        '</mujoco>')
    with open(share / 'urdf' / 'huge.urdf', 'w') as huge:
        huge.write(read_model('tinybot') + ' ' * MAX_MODEL_XML_BYTES)
    return share


def test_what_getspawnables_offers_spawns_and_what_spawnentity_refuses_it_leaves_out(
        world, judged_package):
    response = world.call(GetSpawnables, '/get_spawnables', GetSpawnables.Request(),
                          timeout=30.0)
    assert response.result.result == Result.RESULT_OK, response.result.error_message
    offered = {spawnable.uri for spawnable in response.spawnables}
    message = response.result.error_message
    assert 'package://judged_pkg/mjcf/crate.xml' in offered
    assert spawn_or_fail(world, name='crate', uri='package://judged_pkg/mjcf/crate.xml',
                         initial_pose=stamped(2.0, 0.0, 0.5)) == 'crate'
    before = snapshot(world)
    for name, code in (('mjcf/including.xml', SpawnResult.UNSUPPORTED_ASSETS),
                       ('mjcf/absent.xml', SpawnResult.MISSING_ASSETS),
                       ('urdf/huge.urdf', SpawnResult.RESOURCE_PARSE_ERROR)):
        uri = f'package://judged_pkg/{name}'
        refused = spawn(world, name='judged', uri=uri, initial_pose=stamped(0.0, 3.0, 0.5))
        assert refused.result.result == code, (name, refused.result.error_message)
        reason = refused.result.error_message.removeprefix('SpawnEntity: ')
        assert uri not in offered, name
        assert f'{uri}: {reason}' in message, (name, reason, message)
    assert snapshot(world) == before


# (what is wrong, the fields of both requests, the standard's code)
BAD_REQUESTS = [
    ('an invalid name', {'name': 'r2/d2'}, SpawnResult.NAME_INVALID),
    ('a taken name', {'name': 'tinybot'}, SpawnResult.NAME_NOT_UNIQUE),
    ('an invalid namespace', {'namespace': '9lives'}, SpawnResult.NAMESPACE_INVALID),
    ('an unknown frame', {'frame': 'nowhere'}, SpawnResult.INVALID_POSE),
    ('a position of NaN', {'x': math.nan}, SpawnResult.INVALID_POSE),
    ('a zero quaternion', {'quaternion': (0.0, 0.0, 0.0, 0.0)}, SpawnResult.INVALID_POSE),
    ('XML that does not parse', {'text': '<robot name="b"><link'},
     SpawnResult.RESOURCE_PARSE_ERROR),
    ('a robot MuJoCo does not compile', {'text': TOO_HEAVY}, SpawnResult.RESOURCE_PARSE_ERROR),
]


def both_requests(world, *, name='newcomer', namespace='', frame='', x=0.0,
                  quaternion=(0.0, 0.0, 0.0, 1.0), text=None):
    """Send one bad request both ways; return (lesson's response, standard's response)."""
    text = text or read_model('r2d2')
    pose = stamped(x, 3.0, 1.0, frame=frame, quaternion=quaternion)
    lesson = world.spawn(name, text, pose.pose, frame=frame, namespace=namespace)
    standard = spawn(world, name=name, resource_string=text, entity_namespace=namespace,
                     initial_pose=pose)
    return lesson, standard


@pytest.mark.parametrize('what, fields, code', BAD_REQUESTS, ids=[row[0] for row in BAD_REQUESTS])
def test_a_bad_spawn_reads_the_same_both_ways_and_is_judged_once(world, monkeypatch, what,
                                                                 fields, code):
    before = snapshot(world)
    calls = {'name': 0, 'namespace': 0}

    def counted(key, function):
        def counting(*args, **kwargs):
            calls[key] += 1
            return function(*args, **kwargs)
        return counting
    monkeypatch.setattr(validation, 'check_model_name',
                        counted('name', validation.check_model_name))
    monkeypatch.setattr(node, 'normalise_namespace',
                        counted('namespace', node.normalise_namespace))
    lesson, standard = both_requests(world, **fields)
    monkeypatch.undo()

    assert not lesson.success
    assert standard.result.result == code, standard.result.error_message
    reason = standard.result.error_message.removeprefix('SpawnEntity: ')
    if 'text' in fields:  # each names its own field, and what it takes (the lesson URDF only)
        reason = reason.replace('resource_string', 'model_xml').split(';')[0]
    assert lesson.status_message.startswith(f'SpawnModel: {reason}')
    assert snapshot(world) == before
    # Judged once a request: a text that does not read stops before the namespace; a bad
    # namespace before the world judges the name; anything else reaches the world's checks.
    read = 'text' not in fields or fields['text'] == TOO_HEAVY
    assert calls['namespace'] == (2 if read else 0), calls
    assert calls['name'] == (2 if read and 'namespace' not in fields else 0), calls


def test_a_good_spawn_is_judged_once_too(world, monkeypatch):
    calls = []
    check = validation.check_model_name
    monkeypatch.setattr(validation, 'check_model_name',
                        lambda name: (calls.append(name), check(name))[1])
    assert world.spawn('r2d2', read_model('r2d2'), stamped(-2.0, 1.0, 1.0).pose).success
    assert spawn_or_fail(world, name='crate', resource_string=CRATE,
                         initial_pose=stamped(2.0, 0.0, 0.5)) == 'crate'
    assert calls == ['r2d2', 'crate']


def test_a_spawn_with_no_world_reads_the_same_both_ways(world):
    unloaded = world.call(UnloadWorld, '/unload_world', UnloadWorld.Request()).result
    assert unloaded.result == Result.RESULT_OK, unloaded.error_message
    lesson, standard = both_requests(world)
    assert not lesson.success
    assert standard.result.result == Result.RESULT_OPERATION_FAILED
    reason = standard.result.error_message.removeprefix('SpawnEntity: ')
    assert reason.startswith('no world is loaded')
    assert lesson.status_message == f'SpawnModel: {reason}'
    assert world.models() == []
