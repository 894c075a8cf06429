"""The colcon install space has what `ros2 run` and `ros2 pkg executables` look for."""

from importlib import metadata
import os

from ament_index_python.packages import get_package_prefix, get_package_share_directory

PACKAGE = 'service_tutorial'


def console_scripts():
    entry_points = metadata.distribution(PACKAGE).entry_points
    return sorted(ep.name for ep in entry_points if ep.group == 'console_scripts')


def test_every_console_script_is_an_executable_in_lib_package():
    prefix = get_package_prefix(PACKAGE)
    names = console_scripts()
    assert 'mujoco_world' in names and 'robot_turning_server' in names
    for name in names:
        path = os.path.join(prefix, 'lib', PACKAGE, name)
        assert os.path.isfile(path), f'{path} missing'
        assert os.access(path, os.X_OK), f'{path} is not executable'


def test_package_is_registered_in_the_ament_index():
    prefix = get_package_prefix(PACKAGE)
    marker = os.path.join(prefix, 'share', 'ament_index', 'resource_index', 'packages', PACKAGE)
    assert os.path.isfile(marker)
    for interface_package in ('srv_interfaces',):
        assert get_package_prefix(interface_package)


def test_share_directory_holds_package_xml_models_config_and_launch():
    share = get_package_share_directory(PACKAGE)
    for relative in ('package.xml', 'models/tinybot.urdf', 'models/r2d2.urdf',
                     'config/world.yaml', 'launch/world.launch.py'):
        assert os.path.isfile(os.path.join(share, relative)), f'{relative} not installed'
