"""
simulation_interfaces is the ROS 2 standard's, type for type, and its Python types work.

On the wheels path scripts/setup builds it from scripts/simulation_interfaces; on a sourced
Jazzy it is the system's package. Either way a client built from the real package (Gazebo's,
Isaac Sim's, a user's) must be able to call a world that serves these types, so the type hashes
of what is installed are those of the standard's Jazzy release 1.5.1.
"""

import json
import os
import subprocess
import sys

from ament_index_python.packages import get_package_prefix, get_package_share_directory
import pytest
from rclpy.node import Node
from repository import ROOT
import simulation_interfaces
from simulation_interfaces import action, msg, srv

pytestmark = pytest.mark.ros

DEFINITIONS = os.path.join(ROOT, 'scripts', 'simulation_interfaces')

# Type hashes (RIHS01) of the standard's Jazzy release 1.5.1, as the apt package has them.
TYPE_HASHES = {
    'msg/Bounds': 'e8624fe51f0f5548197542697d924c5699ac7198f1e4c68e50c3ca2af73f5b3f',
    'msg/EntityCategory': '43bdf7933fddf75f6970f7a8fe7078524355d821d390b3954bb46ac36c03dfe1',
    'msg/EntityFilters': '8e7b12e8ea062f14c55de4877221fe1b7cd9749665a7ad8a4ab855fc4b148303',
    'msg/EntityInfo': '3b9a2e7fa00f9a59d325b6e47904044c421561a385682027c7fc06c359806319',
    'msg/EntityState': '2e0464a85eb80a939025075d6c20761eca6a4cb9d6baf2c0ba373467c8b598d0',
    'msg/NamedPose': 'b32da2a039b1840f605ec025b7991a18efacac662fac272818d1ae6e2b12bc27',
    'msg/Resource': '2bb1939cf80f8d2f284afba53cbec60b5ff33759bd39b714128ea8867a34c51a',
    'msg/Result': 'cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17',
    'msg/SimulationState': 'bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415',
    'msg/SimulatorFeatures': '8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305',
    'msg/SpawnEntity': '94a349a865ccf673c18c080520299c88c3d8d5f4842ecf1482d6c997ac4b69f9',
    'msg/SpawnResult': 'dbc277304b6c24bfb2a631cea8f52e2b005d583ec0a6c86b11613f5ce6486da1',
    'msg/Spawnable': '8c22025d840e7a05ab31ba56f998b06458b549a9744b4695be25b778829fc176',
    'msg/TagsFilter': '5c3efc51e8ed04c266c09cb4691ec95b964cd410558e01d8c83646b038826b45',
    'msg/WorldResource': 'e3b65ecf904b9b115673e4a343c6aa3d28c19e185a71228faa64b783afcf2403',
    'srv/DeleteEntity': 'ff7e96a5b83dc8e2bb34b8b034480028b3a24d9f8376b2c0590bac3704be3e28',
    'srv/GetAvailableWorlds': 'ce5589b5523f2732d1969a3c5a7e6b17a387091df8190c62f78d7fdd1109e3e3',
    'srv/GetCurrentWorld': '79ed4e910e1b7a1c9f7950ff758bfba3535bf0dec669054e8af115a099724ddd',
    'srv/GetEntities': 'cb90004c48cd50f37732fb008e22c34c261dd680a723bf0f85d8437ea4498bf7',
    'srv/GetEntitiesStates': '0a76170d0c1c90e1eaf805cfab78ea801d1f82df309a28c1f0fae4b570f19754',
    'srv/GetEntityBounds': '17be8d36231178a5eed0de0344b55c19975581627a9aec30a4fee9926a35deed',
    'srv/GetEntityInfo': '953b7ab6bfc35063f5c9a72463c6ce489baa10249a7fa510926d342a34b0d29e',
    'srv/GetEntityState': '749c91f2a2353d98367b64f2995a0f5842ce92a08ec1ffb3e185540a91557fb5',
    'srv/GetNamedPoseBounds': '59fa8dd2c68ba6771160cc66a628ac99fa95e2748fa0a43c2cc62a2e5f3f6fdc',
    'srv/GetNamedPoses': 'c3d12ab920115bfd4733f6d20516adc3968fb438538540997c37e200e02b04e3',
    'srv/GetSimulationState': '3362dcebee4b1afebbf9c4beee5c79c1455385aded62092a892d61fde8644f30',
    'srv/GetSimulatorFeatures': 'abb9439c8cf196722a469fb6c68b44b484f198c2a1356ac38849a29c2a20a794',
    'srv/GetSpawnables': '3bc0266bf8236058ff589c44512e013afe4f295427c39d44cff363d1c956bf36',
    'srv/LoadWorld': 'f210682338f195f6f06191b46b20ec4992bddf485d33e2cffab2dd15341b4e3e',
    'srv/ResetSimulation': '4ce285d7ff9b8ac70dcc95161f32bf54c05a6f4b13427990e41ab40c36c39646',
    'srv/SetEntityInfo': '867fe2b6812f3e021859171f9b788560d66bb7079d640030baf6c0bb2dd2631e',
    'srv/SetEntityState': 'ca210e7d2b66629ae133c8e1edf5246e618106d75c78ed0556c0e7a33c59ee5e',
    'srv/SetSimulationState': 'a868b916dce49974f637ba252141258c4b07b0c06858b88af560e3eb6bfbcb30',
    'srv/SpawnEntities': '41703a359ee032bf4fc230f144f531705ba039a2e97edeae1f7997dd83b04857',
    'srv/SpawnEntity': 'd4c086345d4194a5fc4c9ae45095736ca4062b5cdac4d06a42dec93d683e03cf',
    'srv/StepSimulation': '913fe0653690ce6bf8f09f316e6a626747012e9fca31e26719910d417aa8565c',
    'srv/UnloadWorld': 'ac7f9a73df1b5b15015d854c5ac552b7726506e22f886c6792804f0b7f88b30b',
    'action/SimulateSteps': 'f0837c898e1219cd73bf4c041feab41e8c533e8e1057e982744dba7b093467eb',
}

# The hashes cover fields only: the constants, which clients compare codes with, are checked on
# their own. Keyed by the message type that holds them.
SPAWN_CODES = {
    'NAME_NOT_UNIQUE': 101, 'NAME_INVALID': 102, 'UNSUPPORTED_FORMAT': 103, 'NO_RESOURCE': 104,
    'NAMESPACE_INVALID': 105, 'RESOURCE_PARSE_ERROR': 106, 'MISSING_ASSETS': 107,
    'UNSUPPORTED_ASSETS': 108, 'INVALID_POSE': 109}
CONSTANTS = {
    'msg/Bounds': {'TYPE_EMPTY': 0, 'TYPE_BOX': 1, 'TYPE_CONVEX_HULL': 2, 'TYPE_SPHERE': 3},
    'msg/EntityCategory': {
        'CATEGORY_OBJECT': 0, 'CATEGORY_ROBOT': 1, 'CATEGORY_HUMAN': 2,
        'CATEGORY_DYNAMIC_OBJECT': 4, 'CATEGORY_STATIC_OBJECT': 5},
    'msg/Result': {
        'RESULT_FEATURE_UNSUPPORTED': 0, 'RESULT_OK': 1, 'RESULT_NOT_FOUND': 2,
        'RESULT_INCORRECT_STATE': 3, 'RESULT_OPERATION_FAILED': 4},
    'msg/SimulationState': {
        'STATE_STOPPED': 0, 'STATE_PLAYING': 1, 'STATE_PAUSED': 2, 'STATE_QUITTING': 3,
        'STATE_NO_WORLD': 4, 'STATE_LOADING_WORLD': 5},
    'msg/SimulatorFeatures': {
        'SPAWNING': 0, 'DELETING': 1, 'NAMED_POSES': 2, 'POSE_BOUNDS': 3, 'ENTITY_TAGS': 4,
        'ENTITY_BOUNDS': 5, 'ENTITY_BOUNDS_BOX': 6, 'ENTITY_BOUNDS_CONVEX': 7,
        'ENTITY_CATEGORIES': 8, 'SPAWNING_RESOURCE_STRING': 9, 'ENTITY_STATE_GETTING': 10,
        'ENTITY_STATE_SETTING': 11, 'ENTITY_INFO_GETTING': 12, 'ENTITY_INFO_SETTING': 13,
        'SPAWNABLES': 14, 'SIMULATION_RESET': 20, 'SIMULATION_RESET_TIME': 21,
        'SIMULATION_RESET_STATE': 22, 'SIMULATION_RESET_SPAWNED': 23,
        'SIMULATION_STATE_GETTING': 24, 'SIMULATION_STATE_SETTING': 25,
        'SIMULATION_STATE_PAUSE': 26, 'STEP_SIMULATION_SINGLE': 31,
        'STEP_SIMULATION_MULTIPLE': 32, 'STEP_SIMULATION_ACTION': 33, 'WORLD_LOADING': 40,
        'WORLD_RESOURCE_STRING': 41, 'WORLD_TAGS': 42, 'WORLD_UNLOADING': 43,
        'WORLD_INFO_GETTING': 44, 'AVAILABLE_WORLDS': 45, 'SPAWNING_ENTITIES': 50},
    'msg/SpawnResult': SPAWN_CODES,
    'msg/TagsFilter': {'FILTER_MODE_ANY': 0, 'FILTER_MODE_ALL': 1},
    'srv/GetAvailableWorlds_Response': {'DEFAULT_SOURCES_FAILED': 101},
    'srv/GetCurrentWorld_Response': {'NO_WORLD_LOADED': 101},
    'srv/LoadWorld_Response': {
        'UNSUPPORTED_FORMAT': 101, 'NO_RESOURCE': 102, 'RESOURCE_PARSE_ERROR': 103,
        'MISSING_ASSETS': 104, 'UNSUPPORTED_ASSETS': 105, 'UNSUPPORTED_ELEMENTS': 106},
    'srv/ResetSimulation_Request': {
        'SCOPE_DEFAULT': 0, 'SCOPE_TIME': 1, 'SCOPE_STATE': 2, 'SCOPE_SPAWNED': 4,
        'SCOPE_ALL': 255},
    'srv/SetEntityState_Response': {'INVALID_POSE': 101},
    'srv/SetSimulationState_Response': {
        'ALREADY_IN_TARGET_STATE': 101, 'STATE_TRANSITION_ERROR': 102,
        'INCORRECT_TRANSITION': 103},
    'srv/SpawnEntities_Response': {'ENTITIES_SPAWN_FAILED': 150},
    'srv/SpawnEntity_Response': SPAWN_CODES,
    'srv/UnloadWorld_Response': {'NO_WORLD_LOADED': 101},
}
MODULES = {'msg': msg, 'srv': srv, 'action': action}
PARTS = {'msg': ('',), 'srv': ('Request', 'Response'), 'action': ('Goal', 'Result', 'Feedback')}


def installed_type_hash(share, interface):
    """Return the type hash rosidl installed for an interface (e.g. 'srv/GetEntities')."""
    with open(os.path.join(share, f'{interface}.json')) as description:
        hashes = json.load(description)['type_hashes']
    return next(entry['hash_string'] for entry in hashes
                if entry['type_name'] == f'simulation_interfaces/{interface}')


def message_types():
    """Return every message type of the package by name, with those inside services and actions."""
    found = {}
    for interface in TYPE_HASHES:
        kind, name = interface.split('/')
        interface_type = getattr(MODULES[kind], name)
        for part in PARTS[kind]:
            found[f'{interface}_{part}' if part else interface] = \
                getattr(interface_type, part) if part else interface_type
    return found


def constants(message_type):
    """Return the constants a generated message type carries, without its fields' defaults."""
    return {name: getattr(message_type, name)
            for name, attribute in vars(type(message_type)).items()
            if isinstance(attribute, property) and not name.endswith('__DEFAULT')}


def test_the_repository_defines_exactly_the_standards_interfaces():
    files = {f'{folder}/{os.path.splitext(name)[0]}'
             for folder in ('msg', 'srv', 'action')
             for name in os.listdir(os.path.join(DEFINITIONS, folder))}
    assert files == set(TYPE_HASHES)


def test_every_installed_type_hashes_like_the_standards_jazzy_release():
    share = get_package_share_directory('simulation_interfaces')
    different = {interface: installed_type_hash(share, interface)
                 for interface, expected in TYPE_HASHES.items()
                 if installed_type_hash(share, interface) != f'RIHS01_{expected}'}
    assert different == {}, 'these types differ from the standard: a real client cannot call them'


def test_the_python_types_are_the_ones_whose_hashes_were_checked():
    prefix = os.path.realpath(get_package_prefix('simulation_interfaces'))
    module = os.path.realpath(simulation_interfaces.__file__)
    assert module.startswith(prefix + os.sep), f'{module} is not from {prefix}'


def test_a_sourced_jazzy_brings_the_package_and_nothing_of_ours_shadows_it():
    prefix = os.path.realpath(get_package_prefix('simulation_interfaces'))
    ours = (os.path.realpath(ROOT) + os.sep, os.path.realpath(sys.prefix) + os.sep)
    if os.environ.get('ROS_DISTRO'):
        assert not (prefix + os.sep).startswith(ours), \
            f'simulation_interfaces comes from {prefix}, not from the sourced Jazzy'
    else:  # the wheels: scripts/setup built it into the virtual environment
        assert prefix == os.path.realpath(sys.prefix)


def test_colcon_finds_no_simulation_interfaces_of_ours_in_a_workspace(tmp_path):
    # As the README's workspace has it: the clone in src/, srv_interfaces named as a base path.
    os.mkdir(tmp_path / 'src')
    os.symlink(ROOT, tmp_path / 'src' / 'service_tutorial')
    listed = subprocess.run(
        [sys.executable, '-m', 'colcon', 'list', '--names-only',
         '--base-paths', 'src', 'src/service_tutorial/srv_interfaces'],
        cwd=tmp_path, capture_output=True, text=True, check=True).stdout.split()
    assert sorted(listed) == ['service_tutorial', 'srv_interfaces']


def test_codes_and_kinds_are_the_standards_constants():
    found = {name: constants(message_type) for name, message_type in message_types().items()}
    assert len(found) == 15 + 2 * 22 + 3
    assert found == {name: CONSTANTS.get(name, {}) for name in found}


def test_a_step_request_steps_once_unless_told_otherwise():
    assert srv.StepSimulation.Request().steps == 1
    assert action.SimulateSteps.Goal().steps == 0


def test_get_simulation_state_answers_a_client_of_the_same_type(ros):
    server = ros.add_node(Node('simulation_state_server'))
    answered = []

    def state_callback(request, response):
        answered.append(request)
        response.state.state = msg.SimulationState.STATE_PAUSED
        response.result.result = msg.Result.RESULT_OK
        response.result.error_message = ''
        return response

    server.create_service(srv.GetSimulationState, 'get_simulation_state', state_callback)
    response = ros.call(srv.GetSimulationState, 'get_simulation_state',
                        srv.GetSimulationState.Request())
    assert len(answered) == 1
    assert response.state.state == msg.SimulationState.STATE_PAUSED
    assert response.result.result == msg.Result.RESULT_OK


def test_spawn_entities_carries_nested_requests_and_results_both_ways(ros):
    server = ros.add_node(Node('spawn_entities_server'))
    received = []

    def spawn_callback(request, response):
        received.extend(request.spawn_requests)
        for spawn in request.spawn_requests:
            result = msg.SpawnResult(entity_name=spawn.name or 'generated_0')
            result.result.result = (msg.Result.RESULT_OK if spawn.entity_resource.uri
                                    else msg.SpawnResult.NO_RESOURCE)
            response.results.append(result)
        response.result.result = srv.SpawnEntities.Response.ENTITIES_SPAWN_FAILED
        response.result.error_message = '1 of 2 failed'
        return response

    server.create_service(srv.SpawnEntities, 'spawn_entities', spawn_callback)
    tinybot = msg.SpawnEntity(name='tinybot', allow_renaming=True, entity_namespace='tb')
    tinybot.entity_resource.uri = 'package://service_tutorial/models/tinybot.urdf'
    tinybot.initial_pose.header.frame_id = 'world'
    tinybot.initial_pose.pose.position.x = 1.5
    response = ros.call(srv.SpawnEntities, 'spawn_entities', srv.SpawnEntities.Request(
        spawn_requests=[tinybot, msg.SpawnEntity()]))
    assert received == [tinybot, msg.SpawnEntity()]
    assert response.result.result == 150
    assert response.result.error_message == '1 of 2 failed'
    assert [(result.entity_name, result.result.result) for result in response.results] == [
        ('tinybot', msg.Result.RESULT_OK), ('generated_0', msg.SpawnResult.NO_RESOURCE)]
