"""
Robot description files as people have them: plain URDF, or xacro expanded with real xacro.

The spawn client and the world node's start-up models read files through read_robot_file();
the spawn service never does: model_xml from the network stays plain URDF, so no request can
make the world read an include. $(find pkg) in a xacro file resolves through the ament index
(AMENT_PREFIX_PATH), as `ros2 run xacro xacro` resolves it.
"""

from dataclasses import dataclass
import os

import xacro

XACRO_NAMESPACE = 'http://www.ros.org/wiki/xacro'
XACRO_EXTENSION = '.xacro'


class RobotFileError(Exception):
    """A robot file that cannot be read or expanded; the message names the file."""


@dataclass(frozen=True)
class RobotFile:
    """A robot description ready for the spawn service: URDF text and the file's folder."""

    urdf: str
    base_dir: str  # where mesh paths relative to the file resolve


def is_xacro(path, text):
    """Tell whether a robot file is xacro: by its extension or by the xacro namespace."""
    return path.endswith(XACRO_EXTENSION) or XACRO_NAMESPACE in text


def file_model_name(path):
    """Return the model name a robot file suggests: robot.urdf.xacro -> robot."""
    name = os.path.basename(path)
    for extension in (XACRO_EXTENSION, '.urdf'):
        name = name[:-len(extension)] if name.endswith(extension) else name
    return name


def parse_xacro_arguments(texts, *, path=''):
    """Return {name: value} of xacro arguments written 'name:=value'."""
    arguments = {}
    for text in texts or ():
        name, separator, value = text.partition(':=')
        if not separator or not name.strip():
            raise RobotFileError(f"xacro argument '{text}' for '{path}' is not name:=value")
        arguments[name.strip()] = value
    return arguments


def expand_xacro(path, arguments=None):
    """Return the URDF text xacro makes of a file, with arguments {name: value}."""
    # xacro writes the defaults of every <xacro:arg> into the mapping it is given and wants
    # str values: hand it a fresh dict of strings each time.
    mappings = {str(name): str(value) for name, value in (arguments or {}).items()}
    try:
        document = xacro.process_file(path, mappings=mappings)
    except Exception as error:  # xacro's own command line reports every exception this way
        raise RobotFileError(f"xacro cannot expand '{path}': {_xacro_reason(error)}") from None
    return document.toxml()


def _xacro_reason(error):
    """Return why xacro failed, in one line."""
    cause = getattr(error, 'exc', None)
    if isinstance(cause, KeyError) and cause.args:
        # A failed $(find): the ament index's own message names the package.
        text = str(cause.args[0])
    else:
        text = str(error) or type(error).__name__
    return ' '.join(line.strip() for line in text.splitlines() if line.strip())


def read_robot_file(path, xacro_arguments=None):
    """Return a RobotFile for a URDF or xacro file; xacro_arguments: {name: value}."""
    path = os.path.abspath(path)
    try:
        with open(path, encoding='utf-8') as robot_file:
            text = robot_file.read()
    except OSError as error:
        raise RobotFileError(
            f"cannot read robot file '{path}': {error.strerror or error}") from None
    except UnicodeDecodeError:
        raise RobotFileError(f"robot file '{path}' is not UTF-8 text") from None
    if is_xacro(path, text):
        text = expand_xacro(path, xacro_arguments)
    elif xacro_arguments:
        raise RobotFileError(f"xacro arguments given for '{path}', which is not a xacro file")
    return RobotFile(urdf=text, base_dir=os.path.dirname(path))
