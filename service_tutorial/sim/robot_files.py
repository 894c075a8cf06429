"""
Robot files, read one way: every robot description the world takes comes in through here.

A description comes by uri (a spawn request, a world file), by a path the world's owner
names (a parameter, the lesson's spawn client), or as text (a request's resource_string, the
lesson's model_xml). Whichever way, it is read with one byte limit and decoded as UTF-8; an
installed .xacro file is expanded with real xacro, as a launch file would ($(find pkg)
resolves through the ament index, as `ros2 run xacro xacro` resolves it); a text is never
expanded, so no request makes the world read an include. The root element tells the format
(description_formats.py), and the RobotSource that comes out is what a SpawnOrder is made of.

A uri is read only from below an installed package's share folder, the roots a robot's meshes
may come from too (package_files.py); other files are refused unopened. Every refusal is a
WorldError with its Reason: NO_RESOURCE, UNSUPPORTED_FORMAT or NOT_PARSEABLE.
"""

import collections
from dataclasses import dataclass
import os

from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.description_formats import FORMATS
from service_tutorial.sim.package_files import confined_path, PackageFileError
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES, parse_xml
from service_tutorial.sim.urdf.hardened_xml import XACRO_NAMESPACE
from service_tutorial.sim.validation import quoted, Reason, WorldError
import xacro

XACRO_EXTENSION = '.xacro'
ALL_FORMATS = tuple(FORMATS)
# Formats of other simulators, named in the refusal: by extension and by root element.
OTHER_EXTENSIONS = {'.world': 'an SDF world, which LoadWorld loads', '.usd': 'USD',
                    '.usda': 'USD', '.usdc': 'USD', '.usdz': 'USD'}
_XACRO_TAG = '{' + XACRO_NAMESPACE + '}'
# Texts told apart lately, kept: a fleet's or a lesson's robot is the same text again and
# again. Only texts up to a size are kept, so that the kept ones never weigh much.
_TOLD_TEXTS = 32
_TOLD_TEXT_CHARACTERS = 1 << 18
_told_texts = collections.OrderedDict()  # (text, base_dir, what, formats, from_file) -> source


@dataclass(frozen=True)
class RobotSource:
    """A robot description read and told apart: its text, format, own name and folder."""

    text: str
    model_format: str  # a name of description_formats.FORMATS: 'urdf' or 'mjcf'
    robot_name: str  # the name its root element gives, '' if none
    base_dir: str = None  # where its relative mesh paths resolve; None for a text


def read_uri(uri, package_share, *, formats=ALL_FORMATS):
    """
    Return the RobotSource of the file a package:// or file:// uri names, or refuse it.

    package_share maps a package name to its share folder (ament's get_package_share_directory);
    formats: the names of the formats the caller takes.
    """
    shown = f'uri {quoted(uri)}'
    scheme = uri.partition('://')[0]
    owner = next((FORMATS[name] for name in formats if scheme in FORMATS[name].uri_schemes),
                 None)
    if owner is not None:
        path = owner.locate(uri, package_share)
    else:
        try:
            path = confined_path(uri, package_share, folder=None)
        except PackageFileError as error:
            raise WorldError(str(error), Reason.NO_RESOURCE) from None
    if os.path.isdir(path):
        path = _model_folder_file(path, shown, formats)
    _check_extension(path, shown, formats)
    return _read_file(path, shown, None, formats)


def read_description_text(path, what):
    """Return the text of a file a description names (an SDF include, a model.config)."""
    return _read_bytes(path, f'{what} {quoted(path)}').decode('utf-8')


def read_path(path, *, xacro_arguments=None, formats=ALL_FORMATS, what='robot file'):
    """
    Return the RobotSource of a robot file (or model folder) named by path, or refuse it.

    xacro_arguments: {name: value} for a xacro file (refused for any other); what: what the
    file is, for the refusal.
    """
    path = os.path.abspath(path)
    shown = f"{what} '{path}'"
    if os.path.isdir(path):
        path = _model_folder_file(path, shown, formats)
    return _read_file(path, shown, xacro_arguments, formats)


def read_text(text, what='resource_string', *, formats=ALL_FORMATS):
    """Return the RobotSource of a description given as text (never expanded), or refuse it."""
    if isinstance(text, bytes):
        try:
            text = text.decode('utf-8')
        except UnicodeDecodeError:
            raise WorldError(f'{what} is not UTF-8 text', Reason.NOT_PARSEABLE) from None
    return _told_or_kept(text, None, what, tuple(formats), False)


def is_xacro(path, text):
    """Tell whether a robot file is xacro: by its extension or by the xacro namespace."""
    return path.endswith(XACRO_EXTENSION) or XACRO_NAMESPACE in text


def file_model_name(path):
    """Return the model name a robot file suggests: robot.urdf.xacro -> robot."""
    name = os.path.basename(path)
    for extension in (XACRO_EXTENSION, '.urdf', '.mjcf', '.xml', '.sdf'):
        name = name[:-len(extension)] if name.endswith(extension) else name
    return name


def parse_xacro_arguments(texts, *, path=''):
    """Return {name: value} of xacro arguments written 'name:=value'."""
    arguments = {}
    for text in texts or ():
        name, separator, value = text.partition(':=')
        if not separator or not name.strip():
            raise WorldError(f"xacro argument '{text}' for '{path}' is not name:=value")
        arguments[name.strip()] = value
    return arguments


def expand_xacro(path, arguments=None):
    """Return the text xacro makes of a file, with arguments {name: value}, or refuse it."""
    # xacro writes the defaults of every <xacro:arg> into the mapping it is given and wants
    # str values: hand it a fresh dict of strings each time.
    mappings = {str(name): str(value) for name, value in (arguments or {}).items()}
    try:
        document = xacro.process_file(path, mappings=mappings)
    except Exception as error:  # xacro's own command line reports every exception this way
        raise WorldError(f"xacro cannot expand '{path}': {_xacro_reason(error)}",
                         Reason.NOT_PARSEABLE) from None
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


def _check_extension(path, shown, formats):
    """Refuse a file whose extension is no robot file of the formats taken, unopened."""
    name = path.lower()
    name = name[:-len(XACRO_EXTENSION)] if name.endswith(XACRO_EXTENSION) else name
    extension = os.path.splitext(name)[1]
    if extension in OTHER_EXTENSIONS:
        raise WorldError(f'{shown} is {OTHER_EXTENSIONS[extension]}; {_reads(formats)}',
                         Reason.UNSUPPORTED_FORMAT)
    known = [known for taken in formats for known in FORMATS[taken].extensions]
    if extension not in known and not path.endswith(XACRO_EXTENSION):
        raise WorldError(f'{shown} is not a {", ".join(known + [XACRO_EXTENSION])} file; '
                         f'{_reads(formats)}', Reason.UNSUPPORTED_FORMAT)


def _model_folder_file(folder, shown, formats):
    """Return the model file of a model folder (SDF's, with a model.config), or refuse it."""
    for name in formats:
        finder = FORMATS[name].folder_file
        path = finder(folder, read_description_text) if finder is not None else None
        if path is not None:
            return path
    raise WorldError(f'{shown} names a folder that is no model folder (of '
                     f'{_listed(formats)})', Reason.NO_RESOURCE)


def _read_bytes(path, shown):
    """Return the bytes of a file, with the byte limit; refuse one that cannot be read."""
    try:
        with open(path, 'rb') as robot_file:
            data = robot_file.read(MAX_MODEL_XML_BYTES + 1)
    except OSError as error:
        raise WorldError(f'{shown} cannot be read: {error.strerror or error}',
                         Reason.NO_RESOURCE) from None
    if len(data) > MAX_MODEL_XML_BYTES:
        raise WorldError(f'{shown} is larger than the limit of {MAX_MODEL_XML_BYTES} bytes',
                         Reason.NOT_PARSEABLE)
    return data


def _read_file(path, shown, xacro_arguments, formats):
    """Return the RobotSource of a file, expanding a xacro file."""
    data = _read_bytes(path, shown)
    try:
        text = data.decode('utf-8')
    except UnicodeDecodeError:
        raise WorldError(f'{shown} is not UTF-8 text', Reason.NOT_PARSEABLE) from None
    if is_xacro(path, text):
        text = expand_xacro(path, xacro_arguments)
    elif xacro_arguments:
        raise WorldError(f'xacro arguments given for {shown}, which is not a xacro file')
    return _told_or_kept(text, os.path.dirname(path), shown, tuple(formats), True)


def _told_or_kept(*key):
    """Return _told(*key), kept from an earlier call when the text is small."""
    if len(key[0]) > _TOLD_TEXT_CHARACTERS:
        return _told(*key)
    source = _told_texts.pop(key, None) or _told(*key)
    _told_texts[key] = source  # the latest last
    while len(_told_texts) > _TOLD_TEXTS:
        _told_texts.popitem(last=False)
    return source


def _told(text, base_dir, what, formats, from_file):
    """Return the RobotSource of a text of one of the formats, or refuse it."""
    data = text.encode('utf-8')
    if len(data) > MAX_MODEL_XML_BYTES:
        raise WorldError(f'{what} is {len(data)} bytes, more than the limit of '
                         f'{MAX_MODEL_XML_BYTES}', Reason.NOT_PARSEABLE)
    if not data.strip():
        raise WorldError(f'{what} is empty', Reason.NOT_PARSEABLE)
    try:
        root = parse_xml(data, what)
    except UrdfError as error:
        raise WorldError(str(error), Reason.NOT_PARSEABLE) from None
    tag = root.tag if isinstance(root.tag, str) else ''
    description_format = next((FORMATS[name] for name in FORMATS if FORMATS[name].root == tag),
                              None)
    if description_format is None:
        kinds = ' nor '.join(name.upper() for name in formats)
        raise WorldError(f'{what} is {"neither " if len(formats) > 1 else "not "}{kinds}: '
                         f'root element is <{tag[:40]}>',
                         Reason.UNSUPPORTED_FORMAT if from_file else Reason.NOT_PARSEABLE)
    if description_format.name not in formats:
        raise WorldError(f'{what} is {description_format.name.upper()} (root element <{tag}>); '
                         f'{_reads(formats)}', Reason.UNSUPPORTED_FORMAT)
    if any(isinstance(element.tag, str) and element.tag.startswith(_XACRO_TAG)
           for element in root.iter()):
        raise WorldError(f'{what} contains xacro macros, which a spawn never expands: run '
                         'xacro on it first, or name an installed .xacro file by its uri',
                         Reason.NOT_PARSEABLE)
    return RobotSource(text=text, model_format=description_format.name,
                       robot_name=description_format.robot_name(root) or '',
                       base_dir=base_dir)


def _reads(formats):
    """Say which formats are taken, for a refusal."""
    if formats == ALL_FORMATS:
        return f'this world spawns {_listed(formats)}'
    return f'here only {_listed(formats)} is taken'


def _listed(names):
    """Return names as 'a', 'a and b' or 'a, b and c'."""
    return ' and '.join(filter(None, (', '.join(names[:-1]), names[-1])))
