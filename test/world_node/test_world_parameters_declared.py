"""
The world node's parameters as declared: types, ranges, descriptions and the values refused.

No world runs here. The parameters are declared on a plain node, as the world node declares
them, and set over ROS as `ros2 param set` does. Every bad value at start-up goes through the
world's own reading in this process (declare_world_parameters under run_or_exit, as the world
node's main() calls it): the line it would write and its exit status. Two of them are also given
to the installed `mujoco_world`, which must end at once with that line, as must web:=true where
viser does not import. What a value does to a running world is test_world_parameters_running's
part.
"""

import itertools
import math
import os
import shutil
import subprocess
import sys
import textwrap

import pytest
from rcl_interfaces.msg import ParameterType
from rcl_interfaces.srv import DescribeParameters
from rclpy.node import Node
from rclpy.parameter import Parameter
from repository import read_file, ROOT
from service_tutorial.world_node.parameters import declare_world_parameters, default_parameters
from service_tutorial.world_node.parameters import run_or_exit, WORLD_PARAMETERS
from service_tutorial.world_node.web.page import VISER_REQUIREMENT
import yaml

pytestmark = pytest.mark.ros

INF = math.inf
T = ParameterType

# What each parameter is meant to be: type, the range its descriptor shows, read-only.
INTENDED = {
    'timestep': (T.PARAMETER_DOUBLE, (0.0, 0.1), True),
    'real_time_factor': (T.PARAMETER_DOUBLE, (0.0, INF), False),
    'paused': (T.PARAMETER_BOOL, None, False),
    'clock_publish_rate': (T.PARAMETER_DOUBLE, (0.0, INF), False),
    'odom_publish_rate': (T.PARAMETER_DOUBLE, (0.0, INF), False),
    'joint_state_publish_rate': (T.PARAMETER_DOUBLE, (0.0, INF), False),
    'cmd_vel_timeout': (T.PARAMETER_DOUBLE, (0.0, INF), False),
    'world': (T.PARAMETER_STRING, None, True),
    'models': (T.PARAMETER_STRING_ARRAY, None, True),
    'model_names': (T.PARAMETER_STRING_ARRAY, None, True),
    'model_namespaces': (T.PARAMETER_STRING_ARRAY, None, True),
    'model_poses': (T.PARAMETER_DOUBLE_ARRAY, None, True),
    'scenery': (T.PARAMETER_STRING, None, True),
    'gui': (T.PARAMETER_BOOL, None, True),
    'web': (T.PARAMETER_BOOL, None, True),
    'web_port': (T.PARAMETER_INTEGER, (1, 65535), True),
    'web_host': (T.PARAMETER_STRING, None, True),
    'camera_enabled': (T.PARAMETER_BOOL, None, False),
    'camera_rate': (T.PARAMETER_DOUBLE, (0.0, INF), False),
    'camera_width': (T.PARAMETER_INTEGER, (1, 4096), False),
    'camera_height': (T.PARAMETER_INTEGER, (1, 4096), False),
    'camera_position': (T.PARAMETER_DOUBLE_ARRAY, None, False),
    'camera_look_at': (T.PARAMETER_DOUBLE_ARRAY, None, False),
    'camera_fovy': (T.PARAMETER_DOUBLE, (0.0, 180.0), False),
    'snapshot_directory': (T.PARAMETER_STRING, None, False),
}

# A value of the wrong type for each parameter, as typed after -p name:=
WRONG_TYPE = {
    'timestep': 'fast', 'real_time_factor': 'true', 'paused': '1',
    'clock_publish_rate': "'250'", 'odom_publish_rate': '[50.0]',
    'joint_state_publish_rate': 'high', 'cmd_vel_timeout': 'false',
    'models': 'tinybot.urdf', 'model_names': '[1, 2]', 'model_namespaces': "''",
    'model_poses': '[a, b, c, d]', 'gui': 'maybe', 'camera_enabled': '0.5',
    'camera_rate': '[10]', 'camera_width': '480.0', 'camera_height': 'tall',
    'camera_position': '1.0', 'camera_look_at': '[a, b, c]', 'camera_fovy': 'wide',
    'snapshot_directory': '42', 'scenery': '[yard.urdf]', 'world': '[yard]',
    'web': 'maybe', 'web_port': 'http', 'web_host': '127',
}

# A value out of range, and how the message writes it back; booleans and the directory have none.
OUT_OF_RANGE = {
    'timestep': ('0.5', '0.5'), 'real_time_factor': ('-1.0', '-1.0'),
    'clock_publish_rate': ('0.0', '0.0'), 'odom_publish_rate': ('-5.0', '-5.0'),
    'joint_state_publish_rate': ('0', '0.0'), 'cmd_vel_timeout': ('-0.1', '-0.1'),
    'models': ("['']", "['']"), 'model_names': ('[a, b]', "['a', 'b']"),
    'model_namespaces': ('[a, b]', "['a', 'b']"), 'model_poses': ('[0.0, 0.0, 0.0]', '0.0]'),
    'camera_rate': ('0.0', '0.0'), 'camera_width': ('0', '0'), 'camera_height': ('5000', '5000'),
    'camera_position': ('[1.0, 2.0]', '[1.0, 2.0]'),
    'camera_look_at': ('[.nan, 0.0, 0.0]', 'nan'), 'camera_fovy': ('180.0', '180.0'),
    'web_port': ('70000', '70000'),
}

_names = (f'world_parameters_{index}' for index in itertools.count())


def node_with(*arguments, **kwargs):
    """Make a plain node with command-line arguments, as `mujoco_world --ros-args ...` gets."""
    return Node(next(_names), cli_args=['--ros-args', *arguments], **kwargs)


def test_config_world_yaml_documents_exactly_the_code_defaults():
    with open(os.path.join(ROOT, 'config', 'world.yaml')) as config_file:
        (node,) = yaml.safe_load(config_file).values()  # mujoco, or a wildcard such as /**
    documented = node['ros__parameters']
    in_code = default_parameters()
    assert list(documented) == list(in_code)  # same names, same order
    assert {name: (type(v), v) for name, v in documented.items()} == \
        {name: (type(v), v) for name, v in in_code.items()}


def test_every_descriptor_as_intended(ros):
    node = ros.add_node(node_with())
    declare_world_parameters(node)
    request = DescribeParameters.Request(names=list(INTENDED))
    descriptors = ros.call(DescribeParameters, f'/{node.get_name()}/describe_parameters',
                           request).descriptors
    assert [d.name for d in descriptors] == list(INTENDED)
    for descriptor in descriptors:
        kind, limits, read_only = INTENDED[descriptor.name]
        assert descriptor.description and descriptor.additional_constraints, descriptor.name
        assert (descriptor.type, descriptor.read_only) == (kind, read_only), descriptor.name
        assert not descriptor.dynamic_typing
        ranges = list(descriptor.floating_point_range) + list(descriptor.integer_range)
        assert [(r.from_value, r.to_value) for r in ranges] == ([limits] if limits else []), \
            descriptor.name
    listed = set(node.get_parameters_by_prefix(''))
    assert listed - {'use_sim_time', 'start_type_description_service'} == set(INTENDED)


NAMES = [spec.name for spec in WORLD_PARAMETERS]
# Bad values checked at start-up: each parameter's wrong type, and its out-of-range value
# where it has one (booleans and the snapshot directory take every value of their type).
START_UP_CASES = [(name, 'wrong type') for name in NAMES] + [
    (name, 'out of range') for name in NAMES if name in OUT_OF_RANGE]
# The cases also given to the installed program: a wrong type and a value out of range.
PROGRAM_CASES = [('timestep', 'wrong type'), ('web_port', 'out of range')]


def bad_argument(name, kind):
    """Return the -p argument of a bad start-up case: name:=value."""
    value = WRONG_TYPE[name] if kind == 'wrong type' else OUT_OF_RANGE[name][0]
    return f'{name}:={value}'


def world_command():
    """Return the command line that starts the installed world node, as `ros2 run` does."""
    executable = shutil.which('mujoco_world')
    return [executable] if executable else [
        sys.executable, '-m', 'service_tutorial.world_node.node']


def read_at_start_up(argument, capsys):
    """
    Read the world's parameters from one -p argument as mujoco_world does; return its ending.

    The reading runs under run_or_exit, as the world node's main() runs it: (exit status, what
    it wrote on stderr), or (None, '') if the value was taken.
    """
    capsys.readouterr()
    node = None

    def read():
        nonlocal node
        node = node_with('-p', argument)
        declare_world_parameters(node)
    try:
        run_or_exit('mujoco_world', read)
        status = None
    except SystemExit as ended:
        status = ended.code
    finally:
        if node is not None:
            node.destroy_node()
    return status, capsys.readouterr().err


def assert_refused_with_one_line(name, kind, status, stderr):
    """Assert a bad start-up value ended the world with status 2 and one line naming it."""
    lines = stderr.strip().splitlines()
    assert status == 2 and len(lines) == 1, stderr
    line = lines[0]
    assert line.startswith('mujoco_world: parameter') and f'{name}:=' in line, line
    assert 'expected ' in line, 'the line must say what is allowed'
    if kind == 'wrong type':
        assert line.startswith(f'mujoco_world: parameter {name}:=')
        assert 'has the wrong type' in line
    else:  # out of range, or (model details) not one per model
        assert OUT_OF_RANGE[name][1] in line


def test_every_parameter_has_a_wrong_type_value_to_try():
    missing = [name for name in NAMES if name not in WRONG_TYPE]
    assert not missing, f'no wrong-type value in WRONG_TYPE: {missing}'


@pytest.mark.parametrize('name, kind', START_UP_CASES)
def test_a_bad_value_at_start_up_ends_the_world_with_one_line_naming_it_and_status_2(
        rclpy_session, capsys, name, kind):
    status, stderr = read_at_start_up(bad_argument(name, kind), capsys)
    assert_refused_with_one_line(name, kind, status, stderr)


@pytest.mark.parametrize('name, kind', PROGRAM_CASES)
def test_the_installed_world_ends_at_once_on_a_bad_value_with_that_line(
        rclpy_session, capsys, name, kind):
    argument = bad_argument(name, kind)
    run = subprocess.run([*world_command(), '--ros-args', '-p', argument],
                         capture_output=True, text=True, timeout=60)
    assert_refused_with_one_line(name, kind, run.returncode, run.stderr)
    assert run.stderr == read_at_start_up(argument, capsys)[1]


# First on the world's PYTHONPATH, it makes `import viser` fail as where viser is not installed.
NO_VISER = "raise ModuleNotFoundError(\"No module named 'viser'\", name='viser')\n"


def test_web_without_viser_ends_the_world_with_how_to_install_it_and_status_2(tmp_path):
    shim = tmp_path / 'no_viser' / 'viser'
    shim.mkdir(parents=True)
    (shim / '__init__.py').write_text(NO_VISER)
    python_path = os.pathsep.join(filter(None, [str(shim.parent), os.environ.get('PYTHONPATH')]))
    run = subprocess.run([*world_command(), '--ros-args', '-p', 'web:=true'],
                         env={**os.environ, 'PYTHONPATH': python_path},
                         capture_output=True, text=True, timeout=60)
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    assert lines[0].startswith('mujoco_world: web:=true needs viser, which does not import here '
                               "(No module named 'viser')"), lines[0]
    assert lines[0].endswith(f"install it with python3 -m pip install '{VISER_REQUIREMENT}'")
    # The viser scripts/setup installs: the line and the set-up never disagree.
    assert f"'{VISER_REQUIREMENT}'" in read_file(os.path.join(ROOT, 'scripts', 'setup'))


def test_defaults_need_no_arguments(rclpy_session):
    node = node_with()
    try:
        assert dict(declare_world_parameters(node)) == {
            name: tuple(value) if isinstance(value, list) else value
            for name, value in default_parameters().items()}
    finally:
        node.destroy_node()


def test_integers_for_numbers_are_accepted_at_start_up(rclpy_session, tmp_path):
    params_file = tmp_path / 'world.yaml'
    params_file.write_text('/**:\n  ros__parameters:\n    clock_publish_rate: 100\n'
                           '    model_poses: [1, 2, 0, 0]\n')
    node = node_with('-p', 'real_time_factor:=0', '-p', 'camera_look_at:=[0, 0, 1]',
                     '--params-file', str(params_file),
                     parameter_overrides=[Parameter('cmd_vel_timeout', value=2)])
    try:
        values = declare_world_parameters(node)
        assert values['real_time_factor'] == 0.0 and type(values['real_time_factor']) is float
        assert values['clock_publish_rate'] == 100.0
        assert values['cmd_vel_timeout'] == 2.0
        assert values['model_poses'] == (1.0, 2.0, 0.0, 0.0)
        assert values['camera_look_at'] == (0.0, 0.0, 1.0)
        assert node.get_parameter('real_time_factor').type_ == Parameter.Type.DOUBLE
        assert node.get_parameter('model_poses').type_ == Parameter.Type.DOUBLE_ARRAY
    finally:
        node.destroy_node()


def test_an_empty_world_and_models_without_details(rclpy_session, tmp_path):
    params_file = tmp_path / 'world.yaml'
    params_file.write_text('/**:\n  ros__parameters:\n    models: []\n')
    node = node_with('--params-file', str(params_file))
    try:
        values = declare_world_parameters(node)
        for name in ('models', 'model_names', 'model_namespaces', 'model_poses'):
            assert values[name] == ()
        assert node.get_parameter('model_poses').type_ == Parameter.Type.DOUBLE_ARRAY
        assert node.describe_parameter('models').read_only
    finally:
        node.destroy_node()
    node = node_with('-p', 'models:=[r2d2.urdf, tinybot.urdf]')
    try:
        values = declare_world_parameters(node)
        assert values['models'] == ('r2d2.urdf', 'tinybot.urdf') and values['model_names'] == ()
    finally:
        node.destroy_node()


def test_an_integer_set_at_run_time_is_taken_as_a_number(ros):
    node = ros.add_node(node_with())
    values = declare_world_parameters(node)
    changes = []
    values.on_change(changes.append)
    result = ros.set_parameter(node.get_name(), 'real_time_factor', 2)
    assert result.successful, result.reason
    assert changes == [{'real_time_factor': 2.0}] and type(values['real_time_factor']) is float
    answer = ros.get_parameter(node.get_name(), 'real_time_factor')
    assert (answer.type, answer.double_value) == (T.PARAMETER_DOUBLE, 2.0)
    result = ros.set_parameter(node.get_name(), 'camera_position', [2, -2, 1])
    assert result.successful, result.reason
    assert values['camera_position'] == (2.0, -2.0, 1.0)


def test_a_read_only_parameter_is_not_set_at_run_time(ros):
    node = ros.add_node(node_with())
    values = declare_world_parameters(node)
    result = ros.set_parameter(node.get_name(), 'timestep', 0.001)
    assert not result.successful and 'timestep' in result.reason
    answer = ros.get_parameter(node.get_name(), 'timestep')
    assert values['timestep'] == 0.002 == answer.double_value


@pytest.mark.parametrize('name, value, words', [
    ('clock_publish_rate', 0, ['clock_publish_rate:=0.0', '> 0.0']),  # an integer
    ('real_time_factor', -1.0, ['real_time_factor', '-1.0']),
    ('real_time_factor', 'fast', ['type']),
    ('camera_width', 0, ['camera_width', '0']),
    ('camera_look_at', [1.0, -1.8, 3.0], ['camera_position', 'camera_look_at', 'no view']),
])
def test_a_bad_run_time_value_is_refused_with_a_reason_and_the_node_goes_on(
        ros, name, value, words):
    node = ros.add_node(node_with())
    values = declare_world_parameters(node)
    changes = []
    values.on_change(changes.append)
    before = values[name]
    result = ros.set_parameter(node.get_name(), name, value)
    assert not result.successful
    for word in words:
        assert word in result.reason
    assert values[name] == before and not changes
    # The node still answers, and takes a good value.
    assert ros.get_parameter(node.get_name(), 'paused').type == T.PARAMETER_BOOL
    result = ros.set_parameter(node.get_name(), 'paused', True)
    assert result.successful and changes == [{'paused': True}]


RUN_TIME = sorted(name for name, (_, _, read_only) in INTENDED.items() if not read_only)


def wrong_type_value(name):
    """Return a value of a type the parameter never takes."""
    return 42 if INTENDED[name][0] == T.PARAMETER_STRING else 'fast'


@pytest.mark.parametrize('name', RUN_TIME)
def test_every_run_time_parameter_refuses_a_wrong_type_and_a_value_out_of_range(ros, name):
    node = ros.add_node(node_with())
    values = declare_world_parameters(node)
    changes = []
    values.on_change(changes.append)
    before = values[name]
    # rclpy's own type check answers a wrong type; the world's checks name the parameter.
    refusals = [(wrong_type_value(name), 'Wrong parameter type')]
    if name in OUT_OF_RANGE:
        text, _ = OUT_OF_RANGE[name]
        refusals.append((yaml.safe_load(text), name))
    for value, words in refusals:
        result = ros.set_parameter(node.get_name(), name, value)
        assert not result.successful, f'{name} took {value}'
        assert words in result.reason, result.reason
    assert values[name] == before and not changes
    assert ros.get_parameter(node.get_name(), 'paused').type == T.PARAMETER_BOOL


def test_on_change_follows_the_names_it_was_given(rclpy_session):
    node = node_with()
    try:
        values = declare_world_parameters(node)
        rates, everything = [], []
        values.on_change(rates.append, ['clock_publish_rate', 'odom_publish_rate'])
        assert 'clock_publish_rate' not in values.unwatched()
        assert 'real_time_factor' in values.unwatched()
        assert 'timestep' not in values.unwatched()  # read-only: nothing to follow
        values.on_change(everything.append)
        assert values.unwatched() == []
        node.set_parameters_atomically([Parameter('clock_publish_rate', value=100.0),
                                        Parameter('paused', value=True)])
        assert rates == [{'clock_publish_rate': 100.0}]
        assert everything == [{'clock_publish_rate': 100.0, 'paused': True}]
        with pytest.raises(KeyError, match='clock_rate'):
            values.on_change(rates.append, ['clock_rate'])
    finally:
        node.destroy_node()


def test_a_failing_change_callback_is_logged_and_the_others_still_run(rclpy_session):
    node = node_with()
    try:
        values = declare_world_parameters(node)
        later = []

        def broken(changes):
            raise RuntimeError('no renderer')
        values.on_change(broken)
        values.on_change(later.append)
        assert node.set_parameters([Parameter('camera_fovy', value=40.0)])[0].successful
        assert later == [{'camera_fovy': 40.0}] and values['camera_fovy'] == 40.0
    finally:
        node.destroy_node()


def test_run_or_exit_passes_results_and_other_errors_through():
    assert run_or_exit('mujoco_world', lambda a, b=0: a + b, 1, b=2) == 3
    with pytest.raises(RuntimeError):
        run_or_exit('mujoco_world', lambda: (_ for _ in ()).throw(RuntimeError('bug')))


NODE_PROGRAM = textwrap.dedent("""\
    import sys

    import rclpy
    from rclpy.node import Node
    from service_tutorial.world_node.parameters import declare_world_parameters, run_or_exit


    def main():
        rclpy.init(args=sys.argv)
        try:
            declare_world_parameters(Node('mujoco'))
        finally:
            rclpy.try_shutdown()


    run_or_exit('mujoco_world', main)
    print('started')
""")


@pytest.mark.parametrize('argument, words', [
    ('real_time_factor:=-1', ['real_time_factor:=-1.0', 'expected a finite number >= 0.0']),
    ('camera_width:=wide', ["camera_width:='wide'", 'an integer from 1 to 4096']),
    ('real_time_factor:=0', []),
])
def test_a_program_ends_with_one_line_and_status_2(tmp_path, argument, words):
    program = tmp_path / 'world_node.py'
    program.write_text(NODE_PROGRAM)
    run = subprocess.run([sys.executable, str(program), '--ros-args', '-p', argument],
                         capture_output=True, text=True, timeout=60)
    if not words:
        assert (run.returncode, run.stdout.strip()) == (0, 'started'), run.stderr
        return
    lines = run.stderr.strip().splitlines()
    assert run.returncode == 2 and len(lines) == 1, run.stderr
    # The program's name, whatever file or module started it.
    assert lines[0].startswith('mujoco_world: parameter ')
    for word in words:
        assert word in lines[0]
