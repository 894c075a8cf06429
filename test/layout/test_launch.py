"""
launch/world.launch.py and config/world.rviz.

Read statically everywhere: the arguments, their defaults and types, the RViz displays. Where
`launch` and `launch_ros` can be imported (a ROS 2 Jazzy install), the launch file is also
loaded and its description checked, and `ros2 launch` is run with every argument the way a user
runs it; the PyPI wheels have neither, so those tests skip there.
world_node/test_world_launch.py tests the launched world under launch_testing.
"""

import ast
import importlib.util
import os
import shutil
import signal
import subprocess
import threading

from ament_index_python.packages import get_package_share_directory
import pytest
from repository import ROOT
from simulation_interfaces.srv import GetEntities
from srv_interfaces.srv import GetModelList
import yaml

LAUNCH_FILE = os.path.join(ROOT, 'launch', 'world.launch.py')
RVIZ_FILE = os.path.join(ROOT, 'config', 'world.rviz')
# What rclpy warns when the middleware drops a service's answer (Fast DDS in Jazzy).
LOST_ANSWER = 'failed to send response (timeout): client will not receive response'

ARGUMENTS = {
    'params_file': "PathJoinSubstitution([FindPackageShare(PACKAGE), 'config', 'world.yaml'])",
    'namespace': "''",
    'use_sim_time': "'true'",
    'gui': "'false'",
    'web': "'false'",
    'web_port': "'8080'",
    'web_host': "'127.0.0.1'",
    'real_time_factor': "'1.0'",
    'turning_server': "'false'",
    'rviz': "'false'",
}
TYPED = {'use_sim_time': 'bool', 'gui': 'bool', 'real_time_factor': 'float', 'web': 'bool',
         'web_port': 'int', 'web_host': 'str'}
DISPLAYS = {  # class: the topic it shows
    'rviz_default_plugins/RobotModel': '/robot_description',
    'rviz_default_plugins/TF': None,
    'rviz_default_plugins/Odometry': '/odom',
    'rviz_default_plugins/LaserScan': '/scan',
    'rviz_default_plugins/Image': '/mujoco/camera/image_raw',
}


def calls_to(tree, name):
    """Return every call of a function or class called name in a syntax tree."""
    return [node for node in ast.walk(tree) if isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name) and node.func.id == name]


def keyword(call, name):
    return next((k.value for k in call.keywords if k.arg == name), None)


@pytest.fixture(scope='module')
def launch_tree():
    with open(LAUNCH_FILE) as launch_file:
        return ast.parse(launch_file.read(), LAUNCH_FILE)


@pytest.fixture(scope='module')
def rviz_config():
    with open(RVIZ_FILE) as rviz_file:
        return yaml.safe_load(rviz_file)


def test_the_launch_arguments_and_their_defaults(launch_tree):
    declared = {}
    for call in calls_to(launch_tree, 'DeclareLaunchArgument'):
        name = ast.literal_eval(call.args[0])
        assert name not in declared, f'{name} declared twice'
        assert ast.literal_eval(keyword(call, 'description')), f'{name} has no description'
        declared[name] = ast.unparse(keyword(call, 'default_value'))
    assert declared == ARGUMENTS
    used = calls_to(launch_tree, 'LaunchConfiguration')
    assert {ast.literal_eval(call.args[0]) for call in used} == set(ARGUMENTS)


def test_typed_arguments_reach_the_nodes_as_parameter_values(launch_tree):
    typed = {}
    for call in calls_to(launch_tree, 'ParameterValue'):
        value = call.args[0]
        if isinstance(value, ast.Call) and ast.unparse(value.func) == 'LaunchConfiguration':
            typed[ast.literal_eval(value.args[0])] = ast.unparse(keyword(call, 'value_type'))
    assert typed == TYPED


def test_the_world_gets_the_params_file_first_and_the_arguments_after_it(launch_tree):
    worlds = [call for call in calls_to(launch_tree, 'Node')
              if ast.unparse(keyword(call, 'executable')) == "'mujoco_world'"]
    assert len(worlds) == 1
    parameters = keyword(worlds[0], 'parameters')
    assert [ast.unparse(element) for element in parameters.elts][0] == 'params_file'
    overrides = {ast.literal_eval(key) for key in parameters.elts[1].keys}
    assert overrides == {'use_sim_time', 'gui', 'real_time_factor', 'web', 'web_port', 'web_host'}
    for node in calls_to(launch_tree, 'Node'):
        assert ast.unparse(keyword(node, 'namespace')) == 'namespace'


def test_rviz_config_shows_the_five_displays_in_odom(rviz_config):
    manager = rviz_config['Visualization Manager']
    assert manager['Global Options']['Fixed Frame'] == 'odom'
    shown = {}
    for display in manager['Displays']:
        topic = display.get('Description Topic', display.get('Topic'))
        shown[display['Class']] = topic['Value'] if topic else None
        assert display['Enabled'], display['Class']
    assert {name: shown.get(name, 'missing') for name in DISPLAYS} == DISPLAYS
    robot_model = next(d for d in manager['Displays']
                       if d['Class'] == 'rviz_default_plugins/RobotModel')
    assert robot_model['Description Source'] == 'Topic'
    assert robot_model['Description Topic']['Durability Policy'] == 'Transient Local'


def test_every_rviz_topic_follows_the_namespace(launch_tree, rviz_config):
    remapped = next(node for node in launch_tree.body if isinstance(node, ast.Assign)
                    and ast.unparse(node.targets[0]) == 'RVIZ_TOPICS')
    topics = {topic for topic in DISPLAYS.values() if topic}
    assert set(ast.literal_eval(remapped.value)) == topics


def test_robot_state_publisher_leaves_robot_description_to_the_world(launch_tree):
    # The world publishes robot_description (transient local) for each robot with topics; a
    # second publisher on the same topic would make RViz show whichever text came last.
    publishers = [call for call in calls_to(launch_tree, 'Node')
                  if ast.unparse(keyword(call, 'executable')) == "'robot_state_publisher'"]
    assert len(publishers) == 1
    assert ast.unparse(keyword(publishers[0], 'remappings')) == '[RSP_DESCRIPTION_REMAP]'
    remap = next(node for node in launch_tree.body if isinstance(node, ast.Assign)
                 and ast.unparse(node.targets[0]) == 'RSP_DESCRIPTION_REMAP')
    source, target = ast.literal_eval(remap.value)
    assert source == 'robot_description' and target.strip('/') != 'robot_description'


def test_rviz_config_and_launch_file_are_installed():
    share = get_package_share_directory('service_tutorial')
    for relative in ('config/world.rviz', 'launch/world.launch.py'):
        with open(os.path.join(share, relative)) as installed, \
                open(os.path.join(ROOT, relative)) as source:
            assert installed.read() == source.read(), f'{relative}: run scripts/setup'


# --- with launch and launch_ros (a ROS 2 Jazzy install) ------------------------------------


@pytest.fixture(scope='module')
def launch_module():
    # The repository's launch/ folder is also importable as `launch` (a namespace package)
    # where the real one is missing: ask for a module only the real one has.
    reason = 'launch and launch_ros are not installed (not on PyPI)'
    pytest.importorskip('launch_ros', reason=reason)
    pytest.importorskip('launch.actions', reason=reason)
    spec = importlib.util.spec_from_file_location('world_launch', LAUNCH_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def launch_context(**arguments):
    from launch import LaunchContext
    context = LaunchContext()
    context.launch_configurations.update(arguments)
    return context


def test_loaded_description_declares_the_arguments_with_their_defaults(launch_module):
    from launch.utilities import perform_substitutions
    description = launch_module.generate_launch_description()
    declared = {argument.name: argument for argument in description.get_launch_arguments()}
    assert set(declared) == set(ARGUMENTS)
    context = launch_context()
    defaults = {name: perform_substitutions(context, argument.default_value)
                for name, argument in declared.items()}
    assert defaults['params_file'] == os.path.join(
        get_package_share_directory('service_tutorial'), 'config', 'world.yaml')
    assert {name: value for name, value in defaults.items() if name != 'params_file'} == {
        name: ast.literal_eval(value) for name, value in ARGUMENTS.items()
        if name != 'params_file'}


def test_loaded_description_starts_the_world_and_the_turning_server(launch_module):
    from launch_ros.actions import Node
    description = launch_module.generate_launch_description()
    nodes = [entity for entity in description.entities if isinstance(entity, Node)]
    assert [(node.node_package, node.node_executable) for node in nodes] == [
        ('service_tutorial', 'mujoco_world'), ('service_tutorial', 'robot_turning_server')]


def test_rviz_false_starts_nothing_and_missing_rviz_is_one_line(launch_module, monkeypatch):
    from launch.actions import LogInfo
    from launch.substitutions import LaunchConfiguration
    from launch.utilities import perform_substitutions
    namespace = LaunchConfiguration('namespace')
    context = launch_context(rviz='false', namespace='', use_sim_time='true')
    assert launch_module.start_rviz(context, namespace) == []
    monkeypatch.setattr(launch_module, 'installed', lambda package: package != 'rviz2')
    context = launch_context(rviz='true', namespace='', use_sim_time='true')
    actions = launch_module.start_rviz(context, namespace)
    assert len(actions) == 1 and isinstance(actions[0], LogInfo)
    message = perform_substitutions(context, actions[0].msg)
    assert 'rviz2' in message and '\n' not in message


def test_rviz_true_starts_rviz_with_the_config(launch_module):
    from launch.substitutions import LaunchConfiguration
    from launch_ros.actions import Node
    if not launch_module.installed('rviz2') or not launch_module.installed(
            'robot_state_publisher'):
        pytest.skip('rviz2 or robot_state_publisher is not installed')
    context = launch_context(rviz='true', namespace='', use_sim_time='true')
    actions = launch_module.start_rviz(context, LaunchConfiguration('namespace'))
    assert [(a.node_package, a.node_executable) for a in actions if isinstance(a, Node)] == [
        ('robot_state_publisher', 'robot_state_publisher'), ('rviz2', 'rviz2')]


# --- ros2 launch, as a user runs it ----------------------------------------------------------


class Ros2Launch:
    """`ros2 launch service_tutorial world.launch.py ...`, its output read as it comes."""

    def __init__(self, *arguments):
        self.lines = []
        self.process = subprocess.Popen(
            ['ros2', 'launch', 'service_tutorial', 'world.launch.py', *arguments],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
        self.reader = threading.Thread(target=self.lines.extend, args=(self.process.stdout,))
        self.reader.start()

    def output(self):
        return ''.join(self.lines)

    def stop(self):
        """Ctrl-C, as a user stops it; kill whatever is left after 30 s."""
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(timeout=30.0)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
        self.reader.join()


def test_ros2_launch_with_every_argument(launch_module, ros, tmp_path):
    if shutil.which('ros2') is None:
        pytest.fail('launch_ros is installed but the ros2 command is not on PATH')
    params_file = tmp_path / 'world.yaml'
    params_file.write_text('/**/mujoco:\n  ros__parameters:\n    timestep: 0.004\n')
    launch = Ros2Launch('namespace:=lesson', f'params_file:={params_file}',
                        'use_sim_time:=false', 'real_time_factor:=0', 'turning_server:=true')
    try:
        ready = ('[lesson.mujoco]: MuJoCo world ready: tinybot, timestep 0.004 s, '
                 'real_time_factor 0.0')
        assert ros.wait_for(lambda: ready in launch.output(), timeout=60.0), launch.output()
        models = ros.call(GetModelList, '/lesson/mujoco/get_model_list', GetModelList.Request(),
                          idempotent=True)
        assert list(models.model_names) == ['tinybot']
        # The standard's services move with the namespace, as everything does.
        entities = ros.call(GetEntities, '/lesson/get_entities', GetEntities.Request(),
                            idempotent=True)
        assert list(entities.entities) == ['tinybot']
        for node in ('lesson/mujoco', 'lesson/robot_turning_server'):
            assert ros.get_parameter(node, 'use_sim_time').bool_value is False, node
        assert ros.get_parameter('lesson/mujoco', 'real_time_factor').double_value == 0.0
        started = '[lesson.robot_turning_server]: ==== Robot Turning Server Started ===='
        assert ros.wait_for(lambda: started in launch.output(), timeout=10.0), launch.output()
    finally:
        launch.stop()
    output = launch.output()
    assert launch.process.returncode == 0, output
    for process in ('mujoco_world-1', 'robot_turning_server-2'):
        assert f'[INFO] [{process}]: process has finished cleanly' in output, output
    # What the nodes print: information only, no warning, error or traceback. But for rclpy's
    # warning (two lines) when the middleware drops an answer to a caller it has not yet
    # matched: the test's own first calls race the discovery of a world just started, and ask
    # again (RosHarness.call).
    printed = [line for line in output.splitlines()
               if line.startswith(('[mujoco_world-1]', '[robot_turning_server-2]'))]
    printed = [line for line, before in zip(printed, [''] + printed)
               if not any(LOST_ANSWER in text for text in (line, before))]
    assert printed and all('] [INFO] [' in line for line in printed), output
