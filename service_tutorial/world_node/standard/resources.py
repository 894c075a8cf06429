"""
Where a spawn request's robot comes from: a package:// or file:// uri, or its text itself.

The text's root element says its format: <robot> is URDF, <mujoco> MJCF (sim/mjcf.py), which
the world loads with the share of the uri's package as the only root its mesh files may come
from; an MJCF resource_string may name no file at all.

A uri is read only from below an installed ament package's share folder, the same roots a
robot's meshes may come from (package_files.py); other files are refused unopened. An
installed .xacro file is expanded with xacro, as a launch file would; a resource_string is
never expanded (a xacro there is refused by the URDF loader). MJCF files end in .xml or .mjcf.
"""

from dataclasses import dataclass
import os

from service_tutorial.robot_files import expand_xacro, is_xacro, RobotFileError
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.package_files import confined_path, PackageFileError
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES, parse_xml
from service_tutorial.sim.validation import quoted
from service_tutorial.world_node.standard.results import Refusal
from simulation_interfaces.msg import SpawnResult

ROBOT_EXTENSIONS = ('.urdf', '.xacro', '.xml', '.mjcf')
# The format of a text by its root element, as SpawnEntity names formats.
FORMATS = {'robot': 'urdf', 'mujoco': 'mjcf'}
SPAWNS = 'this world spawns urdf and mjcf'
# Formats other simulators spawn, named in the refusal.
OTHER_FORMATS = {'.sdf': 'SDF', '.world': 'SDF', '.usd': 'USD', '.usda': 'USD', '.usdc': 'USD',
                 '.usdz': 'USD'}
OTHER_ROOTS = {'sdf': 'SDF'}
XACRO_TAG = '{http://www.ros.org/wiki/xacro}'


@dataclass(frozen=True)
class RobotText:
    """A robot to spawn: its text, the folder its meshes resolve from, its own name, format."""

    urdf: str  # URDF, or MJCF if model_format is 'mjcf'
    base_dir: str  # None for a resource_string
    robot_name: str  # the name of its <robot>, or the model of its <mujoco>; '' if none
    model_format: str = 'urdf'  # 'urdf' or 'mjcf'


def read_resource(uri, resource_string, package_share):
    """
    Return the RobotText of a spawn request's resource (the uri wins), or raise a Refusal.

    package_share maps a package name to its share folder (ament's get_package_share_directory).
    """
    if uri:
        path = resource_path(uri, package_share)
        return robot_text(_read_file(uri, path), os.path.dirname(path), f'uri {quoted(uri)}')
    if not resource_string:
        raise Refusal(SpawnResult.NO_RESOURCE, 'neither uri nor resource_string is given')
    return robot_text(resource_string, None, 'resource_string')


def resource_path(uri, package_share):
    """Return the real path of the robot file a uri names, or refuse it with NO_RESOURCE."""
    shown = quoted(uri)
    try:
        path = confined_path(uri, package_share)
    except PackageFileError as error:
        raise Refusal(SpawnResult.NO_RESOURCE, str(error)) from None
    extension = os.path.splitext(path)[1].lower()
    if extension in OTHER_FORMATS:
        raise Refusal(SpawnResult.UNSUPPORTED_FORMAT, f'uri {shown} is '
                      f'{OTHER_FORMATS[extension]}; {SPAWNS}')
    if extension not in ROBOT_EXTENSIONS:
        raise Refusal(SpawnResult.UNSUPPORTED_FORMAT, f'uri {shown} is not a .urdf, .xacro, '
                      f'.xml or .mjcf file; {SPAWNS}')
    return path


def _read_file(uri, path):
    """Return the URDF text of an allowed file, expanding a xacro file."""
    try:
        with open(path, 'rb') as robot_file:
            data = robot_file.read(MAX_MODEL_XML_BYTES + 1)
    except OSError as error:
        raise Refusal(SpawnResult.NO_RESOURCE,
                      f'uri {quoted(uri)} cannot be read: {error.strerror}') from None
    if len(data) > MAX_MODEL_XML_BYTES:
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR, f'uri {quoted(uri)} is larger than '
                      f'the limit of {MAX_MODEL_XML_BYTES} bytes')
    try:
        text = data.decode('utf-8')
    except UnicodeDecodeError:
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR,
                      f'uri {quoted(uri)} is not UTF-8 text') from None
    if is_xacro(path, text):
        try:
            return expand_xacro(path)
        except RobotFileError as error:
            raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR, str(error)) from None
    return text


def robot_text(text, base_dir, what):
    """Check that text is URDF or MJCF (no other format); return its RobotText, or refuse it."""
    data = text.encode('utf-8') if isinstance(text, str) else bytes(text)
    if len(data) > MAX_MODEL_XML_BYTES:
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR, f'{what} is {len(data)} bytes, more '
                      f'than the limit of {MAX_MODEL_XML_BYTES}')
    if not data.strip():
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR, f'{what} is empty')
    try:
        root = parse_xml(data, what)
    except UrdfError as error:
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR, str(error)) from None
    tag = root.tag if isinstance(root.tag, str) else ''
    if tag in OTHER_ROOTS:
        raise Refusal(SpawnResult.UNSUPPORTED_FORMAT, f'{what} is {OTHER_ROOTS[tag]} '
                      f'(root element <{tag}>); {SPAWNS}')
    if tag not in FORMATS:
        code = SpawnResult.UNSUPPORTED_FORMAT if base_dir else SpawnResult.RESOURCE_PARSE_ERROR
        raise Refusal(code, f'{what} is neither URDF nor MJCF: root element is <{tag[:40]}>')
    if tag == 'mujoco':
        return RobotText(urdf=text, base_dir=base_dir, robot_name=root.get('model') or '',
                         model_format='mjcf')
    if any(isinstance(element.tag, str) and element.tag.startswith(XACRO_TAG)
           for element in root.iter()):
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR, f'{what} contains xacro macros, '
                      'which a spawn never expands; an installed .xacro file may be spawned '
                      'by its uri')
    return RobotText(urdf=text, base_dir=base_dir, robot_name=root.get('name') or '')
