"""
Where a spawn request's robot comes from: a package:// or file:// uri, or the URDF text itself.

A uri is read only from below an installed ament package's share folder, the same roots a
robot's meshes may come from (package_files.py); other files are refused unopened. An
installed .xacro file is expanded with xacro, as a launch file would; a resource_string is
never expanded (a xacro there is refused by the URDF loader).
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

ROBOT_EXTENSIONS = ('.urdf', '.xacro')
# Formats other simulators spawn, named in the refusal: this world spawns URDF.
OTHER_FORMATS = {'.sdf': 'SDF', '.world': 'SDF', '.xml': 'MJCF', '.mjcf': 'MJCF',
                 '.usd': 'USD', '.usda': 'USD', '.usdc': 'USD', '.usdz': 'USD'}
OTHER_ROOTS = {'sdf': 'SDF', 'mujoco': 'MJCF'}
XACRO_TAG = '{http://www.ros.org/wiki/xacro}'


@dataclass(frozen=True)
class RobotText:
    """A robot to spawn: its URDF text, the folder its meshes resolve from, its own name."""

    urdf: str
    base_dir: str  # None for a resource_string
    robot_name: str  # the name of its <robot>, '' if it has none


def read_resource(uri, resource_string, package_share):
    """
    Return the RobotText of a spawn request's resource (the uri wins), or raise a Refusal.

    package_share maps a package name to its share folder (ament's get_package_share_directory).
    """
    if uri:
        path = resource_path(uri, package_share)
        return robot_text(_read_file(uri, path), os.path.dirname(path), quoted(uri))
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
                      f'{OTHER_FORMATS[extension]}; this world spawns urdf')
    if extension not in ROBOT_EXTENSIONS:
        raise Refusal(SpawnResult.UNSUPPORTED_FORMAT, f'uri {shown} is not a .urdf or '
                      '.xacro file; this world spawns urdf')
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
    """Check that text is URDF (no other format) and return its RobotText, or refuse it."""
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
                      f'(root element <{tag}>); this world spawns urdf')
    if tag != 'robot':
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR,
                      f'{what} is not URDF: root element is <{tag[:40]}>')
    if any(isinstance(element.tag, str) and element.tag.startswith(XACRO_TAG)
           for element in root.iter()):
        raise Refusal(SpawnResult.RESOURCE_PARSE_ERROR, f'{what} contains xacro macros, '
                      'which a spawn never expands; an installed .xacro file may be spawned '
                      'by its uri')
    return RobotText(urdf=text, base_dir=base_dir, robot_name=root.get('name') or '')
