"""The shape of the simulation core: small files and classes, and no ROS inside."""

import ast
import os

import pytest
from repository import ROOT

CORE = os.path.join(ROOT, 'service_tutorial', 'sim')
MAX_FILE_LINES = 500
MAX_CLASS_LINES = 350
# Top-level packages that belong to ROS, besides every *_msgs, *_srvs and *_interfaces.
ROS_PACKAGES = {'rclpy', 'rcl_interfaces', 'ament_index_python', 'launch', 'launch_ros',
                'rosidl_runtime_py', 'rosidl_parser', 'rpyutils', 'tf2_ros', 'message_filters'}


def core_files():
    return sorted(os.path.join(folder, name) for folder, _, names in os.walk(CORE)
                  for name in names if name.endswith('.py'))


def imported_modules(tree):
    """Return every module an import statement names, wherever the statement is."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            yield node.module


def is_ros(module):
    top = module.split('.')[0]
    return top in ROS_PACKAGES or top.endswith(('_msgs', '_srvs', '_interfaces'))


def test_the_checks_see_ros_when_it_is_there():
    tree = ast.parse('def f():\n    import rclpy.node\n    from std_msgs.msg import String\n')
    assert [module for module in imported_modules(tree) if is_ros(module)] == [
        'rclpy.node', 'std_msgs.msg']
    assert not is_ros('mujoco') and not is_ros('service_tutorial.sim.world')


@pytest.mark.parametrize('path', core_files(), ids=lambda path: os.path.relpath(path, CORE))
def test_core_module_is_small_and_free_of_ros(path):
    with open(path) as source_file:
        source = source_file.read()
    assert len(source.splitlines()) <= MAX_FILE_LINES
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef):
            assert node.end_lineno - node.lineno + 1 <= MAX_CLASS_LINES, node.name
    for module in imported_modules(tree):
        assert not is_ros(module), module
        # The core may use the rest of the package only through the core itself.
        if module.startswith('service_tutorial'):
            assert module.startswith('service_tutorial.sim'), module
