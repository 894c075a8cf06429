"""
The package's shape: files and classes of a readable size, and imports that go one way only.

The simulation imports nothing of ROS and nothing of the package outside sim/; the world node
imports none of its clients: the lesson (nor lesson_world.py, which composes the two), the
pictures, testing/; the lesson reaches the world through ROS, importing of the world node only
the web page's Panel and PageClient, which its panel extends, and of the simulation only the
reader of robot files (for the files it sends) and its refusal; the plugins import nothing of the
URDF builder, which imports them. Each rule has a self-test that shows it catches a violation.
The lesson's material lives in lesson/: its web panel, its turning input, R2-D2's spawn pose
and the turning limits, each written once.
"""

import ast
import os

import pytest
from repository import ROOT

PACKAGE = os.path.join(ROOT, 'service_tutorial')
LESSON = os.path.join(PACKAGE, 'lesson')
MAX_FILE_LINES = 500
MAX_CLASS_LINES = 500
# What belongs to ROS, by a module's top-level package: client libraries, interfaces, tools.
ROS_MODULES = ('rclpy', 'rcl_interfaces', 'srv_interfaces', 'rosidl_runtime_py', 'rmw',
               'rpyutils', 'tf2_ros', 'message_filters')
ROS_PREFIXES = ('ament_', 'launch', 'rosidl_')
ROS_SUFFIXES = ('_msgs', '_srvs', '_interfaces')
# What the lesson's web panel does, which the world node's code never names (lowercased).
LESSON_NAMES = ('r2d2', 'r2-d2', 'control_robot_angle')


def python_files(folder):
    """Return every Python file under folder, sorted."""
    return sorted(os.path.join(directory, name)
                  for directory, _, names in os.walk(folder) if '__pycache__' not in directory
                  for name in names if name.endswith('.py'))


def parse(path):
    with open(path, encoding='utf-8') as source:
        return ast.parse(source.read(), filename=path)


def relative(path):
    return os.path.relpath(path, ROOT)


def module_package(path):
    """Return the dotted name of the package a file of the repository belongs to."""
    return '.'.join(os.path.relpath(os.path.dirname(path), ROOT).split(os.sep))


def imported_modules(tree, package=''):
    """Return (line, dotted name) of everything a module imports, at any depth, dynamically too."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            module = node.module
            if node.level:  # relative to the file's package
                parts = package.split('.')
                base = '.'.join(parts[:len(parts) - node.level + 1])
                module = f'{base}.{node.module}' if node.module else base
            # Each name imported may be a module itself: from service_tutorial import sim.
            found += [(node.lineno, f'{module}.{alias.name}') for alias in node.names]
        elif isinstance(node, ast.Call) and node.args and \
                isinstance(node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
            function = node.func
            name = function.attr if isinstance(function, ast.Attribute) else getattr(
                function, 'id', '')
            if name in ('import_module', '__import__'):
                found.append((node.lineno, node.args[0].value))
    return found


def is_ros(module):
    """Tell whether a module belongs to ROS (its top-level package decides)."""
    top = module.split('.')[0]
    return top in ROS_MODULES or top.startswith(ROS_PREFIXES) or top.endswith(ROS_SUFFIXES)


def within(module, *packages):
    """Tell whether a module is one of these packages or lies inside one of them."""
    return any(module == package or module.startswith(package + '.') for package in packages)


def is_ros_side(module):
    """Tell whether a module is ROS, or a module of this package outside the simulation."""
    return is_ros(module) or (within(module, 'service_tutorial')
                              and not within(module, 'service_tutorial.sim'))


def is_a_client_of_the_world(module):
    """Tell whether a module is of the lesson, the pictures or the testing of the world."""
    return within(module, 'service_tutorial.lesson', 'service_tutorial.lesson_world',
                  'service_tutorial.pictures', 'service_tutorial.testing')


def reaches_past_ros(module):
    """Tell whether a module is of the world's code or of its other clients, for the lesson."""
    if within(module, 'service_tutorial.world_node.web.panel',
              'service_tutorial.world_node.web.page_client'):
        return False  # what the lesson's web panel extends
    if within(module, 'service_tutorial.sim.robot_files', 'service_tutorial.sim.validation'):
        return False  # the one reader of robot files, for the files the lesson sends
    return within(module, 'service_tutorial.sim', 'service_tutorial.world_node',
                  'service_tutorial.lesson_world', 'service_tutorial.pictures',
                  'service_tutorial.testing')


def is_urdf_builder(module):
    return within(module, 'service_tutorial.sim.urdf')


# Which folder of the package may not import what: (folder, forbidden(module), what it is).
IMPORT_RULES = {
    'sim': ('sim', is_ros_side, 'ROS, or the package outside sim/'),
    'world_node': ('world_node', is_a_client_of_the_world,
                   'the lesson, the pictures or testing/'),
    'lesson': ('lesson', reaches_past_ros,
               "the world (but the web page's Panel and PageClient and the reader of robot "
               'files), the pictures or testing/'),
    'plugins': (os.path.join('sim', 'plugins'), is_urdf_builder, 'the URDF builder, sim/urdf/'),
}
# For each rule, a module of its folder that breaks it and one that keeps it.
IMPORT_RULE_EXAMPLES = {
    'sim': ('service_tutorial.sim.urdf',
            'from ...world_node import pacing\n',
            'from .. import frames\nfrom ..plugins import diff_drive\nimport numpy\n'),
    'world_node': ('service_tutorial.world_node.faces',
                   'def snapshot():\n    from ...pictures.image_files import write_png\n',
                   'from ...sim.world import World\nfrom service_tutorial import conversions\n'),
    'lesson': ('service_tutorial.lesson',
               'from ..world_node.node import MujocoWorld\n',
               'from ..world_node.web.panel import Panel\nfrom . import r2d2\nimport rclpy\n'),
    'plugins': ('service_tutorial.sim.plugins',
                'from ..urdf.hardened_xml import parse_numbers\n',
                'from ..description import UrdfError\nfrom service_tutorial.sim import frames\n'),
}


def offenders(rule, tree, package):
    """Return the (line, module) a module imports against a rule."""
    _, forbidden, _ = IMPORT_RULES[rule]
    return [(line, module) for line, module in imported_modules(tree, package)
            if forbidden(module)]


def test_the_import_walk_finds_ros_wherever_it_is_imported():
    tree = ast.parse('import os\n'
                     'def render():\n'
                     '    from sensor_msgs.msg import Image\n'
                     '    import rclpy.node\n'
                     '    return importlib.import_module("ament_index_python")\n'
                     'from . import frames\n'
                     'from .. import conversions\n'
                     'from ..sim.plugins import diff_drive\n')
    modules = [module for _, module in imported_modules(tree, 'service_tutorial.sim')]
    assert sorted(modules) == sorted([
        'os', 'sensor_msgs.msg.Image', 'rclpy.node', 'ament_index_python',
        'service_tutorial.sim.frames', 'service_tutorial.conversions',
        'service_tutorial.sim.plugins.diff_drive'])
    assert sorted(module for module in modules if is_ros_side(module)) == sorted([
        'sensor_msgs.msg.Image', 'rclpy.node', 'ament_index_python',
        'service_tutorial.conversions'])
    assert not is_ros_side('service_tutorial.sim')
    assert is_ros_side('service_tutorial.world_node.pacing')
    assert is_ros_side('service_tutorial.simulator'), 'a sibling is not inside sim/'
    for module in ('std_srvs.srv', 'srv_interfaces.srv', 'rcl_interfaces.msg', 'std_msgs.msg',
                   'launch_ros.actions', 'builtin_interfaces.msg', 'rosgraph_msgs.msg',
                   'rosidl_parser', 'rpyutils', 'tf2_ros', 'message_filters'):
        assert is_ros(module), module
    for module in ('mujoco', 'numpy', 'yourdfpy', 'lxml.etree', 'service_tutorial.sim.world'):
        assert not is_ros(module), module


@pytest.mark.parametrize('rule', sorted(IMPORT_RULES))
def test_each_import_rule_catches_a_module_that_breaks_it(rule):
    package, breaking, keeping = IMPORT_RULE_EXAMPLES[rule]
    assert [line for line, _ in offenders(rule, ast.parse(breaking), package)] == [
        len(breaking.splitlines())]
    assert offenders(rule, ast.parse(keeping), package) == []


@pytest.mark.parametrize('rule', sorted(IMPORT_RULES))
def test_imports_go_one_way(rule):
    folder, _, what = IMPORT_RULES[rule]
    files = python_files(os.path.join(PACKAGE, folder))
    assert files, f'no Python files under {relative(os.path.join(PACKAGE, folder))}'
    found = [f'{relative(path)}:{line}: {module}' for path in files
             for line, module in offenders(rule, parse(path), module_package(path))]
    assert not found, f'{folder}/ imports {what}:\n' + '\n'.join(found)


def test_no_file_is_longer_than_500_lines():
    too_long = []
    for path in python_files(PACKAGE):
        with open(path, encoding='utf-8') as source:
            lines = len(source.read().splitlines())
        if lines > MAX_FILE_LINES:
            too_long.append(f'{relative(path)}: {lines} lines')
    assert not too_long, f'over {MAX_FILE_LINES} lines:\n' + '\n'.join(too_long)


def test_no_class_is_longer_than_500_lines():
    too_long = []
    for path in python_files(PACKAGE):
        for node in ast.walk(parse(path)):
            if isinstance(node, ast.ClassDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_CLASS_LINES:
                    too_long.append(f'{relative(path)}:{node.lineno}: class {node.name}, '
                                    f'{lines} lines')
    assert not too_long, f'over {MAX_CLASS_LINES} lines:\n' + '\n'.join(too_long)


def test_the_package_logs_only_through_core_logger():
    # A logger taken straight from logging inherits the propagation of whatever logger class is
    # installed, and launch's does not propagate: its records would miss /rosout and the root.
    direct = [f'{relative(path)}:{node.lineno}' for path in python_files(PACKAGE)
              if os.path.basename(path) != 'core_logs.py' for node in ast.walk(parse(path))
              if isinstance(node, ast.Call) and ast.unparse(node.func) == 'logging.getLogger']
    assert not direct, 'logging.getLogger instead of core_logger():\n' + '\n'.join(direct)


def test_the_lessons_panel_lives_in_lesson_and_the_world_node_names_none_of_it():
    panels = {}  # file -> the classes in it that extend the web page's Panel
    for path in python_files(PACKAGE):
        for node in ast.walk(parse(path)):
            if isinstance(node, ast.ClassDef) and any(
                    ast.unparse(base).split('.')[-1] == 'Panel' for base in node.bases):
                panels.setdefault(relative(path), []).append(node.name)
    assert panels.get(relative(os.path.join(LESSON, 'web_panel.py'))) == ['LessonPanel']
    in_world_node = [path for path in panels if path.startswith(relative(
        os.path.join(PACKAGE, 'world_node')) + os.sep)]
    assert not in_world_node, f'panels in world_node/: {in_world_node}'
    # What the lesson's panel does is named nowhere in the world node: R2-D2, the turn.
    naming = []
    for path in python_files(os.path.join(PACKAGE, 'world_node')):
        with open(path, encoding='utf-8') as source:
            text = source.read().lower()
        naming += [f'{relative(path)}: {name}' for name in LESSON_NAMES if name in text]
    assert not naming, "world_node/ names the lesson's material:\n" + '\n'.join(naming)


def test_mujoco_world_hands_the_lessons_panel_to_the_world_node():
    with open(os.path.join(ROOT, 'setup.py'), encoding='utf-8') as setup_file:
        assert "'mujoco_world = service_tutorial.lesson_world:main'" in setup_file.read()
    composing = parse(os.path.join(PACKAGE, 'lesson_world.py'))
    assert 'service_tutorial.lesson.web_panel.LessonPanel' in [
        module for _, module in imported_modules(composing, 'service_tutorial')]


def test_turning_input_lives_in_lesson():
    found = [relative(path) for path in python_files(PACKAGE)
             if os.path.basename(path) == 'turning_input.py']
    assert found == [relative(os.path.join(LESSON, 'turning_input.py'))]


def numbers_written(tree):
    """Return the numeric constants and tuples of numeric constants a module writes."""
    def number(node):
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub):
            value = number(node.operand)
            return None if value is None else -value
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            return node.value
        return None
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Tuple):
            values = [number(element) for element in node.elts]
            if values and None not in values:
                found.append(tuple(values))
        elif number(node) is not None:
            found.append(number(node))
    return found


def test_numbers_written_finds_constants_and_tuples():
    tree = ast.parse('A = (-2.0, 1.0, 1.0)\nB = 1.5707\nC = (x, 1.0)\nD = -3\n')
    written = numbers_written(tree)
    assert (-2.0, 1.0, 1.0) in written and 1.5707 in written and -3 in written
    assert (1.0,) not in written


@pytest.mark.parametrize('what, value, home', [
    ("R2-D2's spawn position", (-2.0, 1.0, 1.0), 'r2d2.py'),
    ("the lesson's top angular velocity", 1.5707, 'turning_input.py'),
])
def test_the_lessons_numbers_are_written_once_in_lesson(what, value, home):
    written = [relative(path) for path in python_files(PACKAGE)
               if value in numbers_written(parse(path))]
    assert written == [relative(os.path.join(LESSON, home))], f'{what} written in {written}'
