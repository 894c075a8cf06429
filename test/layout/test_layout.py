"""The package's shape: files and classes of a readable size, and no ROS in the simulation."""

import ast
import os

from repository import ROOT

PACKAGE = os.path.join(ROOT, 'service_tutorial')
SIMULATION = os.path.join(PACKAGE, 'sim')
MAX_FILE_LINES = 500
MAX_CLASS_LINES = 350
# Top-level modules that are ROS, whatever the package: client libraries, interfaces, tools.
ROS_MODULES = ('rclpy', 'rcl_interfaces', 'srv_interfaces', 'rosidl_runtime_py', 'rmw')
ROS_PREFIXES = ('ament_', 'launch', 'rosidl_')
ROS_SUFFIXES = ('_msgs', '_srvs', '_interfaces')


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


def is_ros_side(module):
    """Tell whether a module is ROS, or a module of this package outside the simulation."""
    parts = module.split('.')
    return is_ros(module) or (parts[0] == 'service_tutorial' and parts[1:2] != ['sim'])


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
    for module in ('std_srvs.srv', 'srv_interfaces.srv', 'rcl_interfaces.msg',
                   'launch_ros.actions', 'builtin_interfaces.msg', 'rosgraph_msgs.msg'):
        assert is_ros(module), module
    for module in ('mujoco', 'numpy', 'yourdfpy', 'lxml.etree', 'service_tutorial.sim.world'):
        assert not is_ros(module), module


def test_the_simulation_imports_nothing_of_ros():
    files = python_files(SIMULATION)
    assert files, f'no Python files under {relative(SIMULATION)}'
    offenders = [f'{relative(path)}:{line}: {module}' for path in files
                 for line, module in imported_modules(parse(path), module_package(path))
                 if is_ros_side(module)]
    assert not offenders, 'ROS imported by the simulation:\n' + '\n'.join(offenders)


def test_no_file_is_longer_than_500_lines():
    offenders = []
    for path in python_files(PACKAGE):
        with open(path, encoding='utf-8') as source:
            lines = len(source.read().splitlines())
        if lines > MAX_FILE_LINES:
            offenders.append(f'{relative(path)}: {lines} lines')
    assert not offenders, f'over {MAX_FILE_LINES} lines:\n' + '\n'.join(offenders)


def test_no_class_is_longer_than_350_lines():
    offenders = []
    for path in python_files(PACKAGE):
        for node in ast.walk(parse(path)):
            if isinstance(node, ast.ClassDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_CLASS_LINES:
                    offenders.append(f'{relative(path)}:{node.lineno}: class {node.name}, '
                                     f'{lines} lines')
    assert not offenders, f'over {MAX_CLASS_LINES} lines:\n' + '\n'.join(offenders)
