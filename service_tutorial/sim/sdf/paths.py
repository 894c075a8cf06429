"""
Where an SDF file's uris lead: the models it includes and the meshes it names.

As gz-sim resolves them (../shared/gazebo-harmonic.md, section 1): model://<name>/<rest> in
the folders of GZ_SIM_RESOURCE_PATH (and of the older IGN_GAZEBO_RESOURCE_PATH and
GAZEBO_MODEL_PATH, which Jazzy's users still set), then in every installed package's models/
folder; package://<package>/<rest> in the package's share, then in those folders;
file:// and absolute paths as they are; a relative path against the folder of the SDF file
that names it. Whatever a uri names must lie inside the roots once links are followed: the
resource folders, the installed packages' shares, and the root of the file naming it (the
share or resource folder holding it, or else its own folder); '..' and links that lead out
are refused, as is every uri on the network but the two Fuel models every Gazebo world
includes, OpenRobotics' "Ground Plane" and "Sun", which are built in. Nothing here opens a
file: a model folder's model.config is read by the caller's reader and handed in as text.
"""

import os
import urllib.parse

from service_tutorial.sim.package_files import installed_shares_of, within
from service_tutorial.sim.urdf.hardened_xml import parse_xml
from service_tutorial.sim.urdf.meshes import share_holding
from service_tutorial.sim.validation import quoted

RESOURCE_PATH_VARIABLES = ('GZ_SIM_RESOURCE_PATH', 'IGN_GAZEBO_RESOURCE_PATH',
                           'GAZEBO_MODEL_PATH')
MODELS_FOLDER = 'models'
MODEL_CONFIG = 'model.config'
MAX_URI_LENGTH = 4096
# The newest SDF the world reads, as (major, minor).
NEWEST_VERSION = (1, 11)
FUEL_HOSTS = ('fuel.gazebosim.org', 'fuel.ignitionrobotics.org')
# The Fuel models every Gazebo world includes, by owner and name (lower case), written here
# from Fuel's descriptions: a static 100 m square plane, and a directional light.
GROUND_PLANE = """<sdf version="1.11">
  <model name="ground_plane">
    <static>true</static>
    <link name="link">
      <collision name="collision">
        <geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry>
      </collision>
      <visual name="visual">
        <geometry><plane><normal>0 0 1</normal><size>100 100</size></plane></geometry>
        <material>
          <ambient>0.8 0.8 0.8 1</ambient>
          <diffuse>0.8 0.8 0.8 1</diffuse>
        </material>
      </visual>
    </link>
  </model>
</sdf>
"""
SUN = """<sdf version="1.11">
  <light type="directional" name="sun">
    <cast_shadows>true</cast_shadows>
    <pose>0 0 10 0 0 0</pose>
    <diffuse>0.8 0.8 0.8 1</diffuse>
    <specular>0.2 0.2 0.2 1</specular>
    <direction>-0.5 0.1 -0.9</direction>
  </light>
</sdf>
"""
BUILT_IN = {('openrobotics', 'ground plane'): GROUND_PLANE, ('openrobotics', 'sun'): SUN}


class UriRefused(Exception):
    """A uri that names what an SDF file may not have read; the message names it and why."""


class UriMissing(Exception):
    """A uri that is allowed but names nothing that is there; the message says where it looked."""

    def __init__(self, shown, reason):
        """Say that shown (what names the uri, and the uri) names nothing, for reason."""
        super().__init__(f'{shown}: {reason}')
        self.reason = reason


def parse_version(text, what):
    """Return an SDF version 'X.Y' as (X, Y), or raise ValueError naming what holds it."""
    parts = (text or '').strip().split('.')
    if len(parts) != 2 or not all(part.isdigit() and len(part) <= 3 for part in parts):
        raise ValueError(f'{what} has version {quoted(text or "")}, not X.Y')
    return int(parts[0]), int(parts[1])


def built_in(uri):
    """Return the SDF text of a built-in Fuel model a uri names, or None."""
    parsed = urllib.parse.urlsplit(uri)
    if parsed.scheme not in ('http', 'https') or parsed.hostname not in FUEL_HOSTS:
        return None
    parts = [urllib.parse.unquote(part) for part in parsed.path.split('/') if part]
    # /1.0/<owner>/models/<name>[/<version>[/files...]]
    if len(parts) < 4 or parts[2].lower() != 'models':
        return None
    if len(parts) > 4 and not (len(parts) == 5 and (parts[4].isdigit() or parts[4] == 'tip')):
        return None
    return BUILT_IN.get((parts[1].lower(), ' '.join(parts[3].lower().split())))


def model_file(folder, config_text):
    """
    Return the path of the SDF file a model folder's model.config names, or raise UriRefused.

    The highest <sdf version> up to NEWEST_VERSION is taken, a file without a version only if
    none has one; the file must lie in the folder.
    """
    shown = quoted(os.path.join(folder, MODEL_CONFIG))
    try:
        root = parse_xml(config_text.encode('utf-8'), shown)
    except ValueError as error:
        raise UriRefused(str(error)) from None
    candidates = []
    for entry in root.findall('sdf'):
        name = (entry.text or '').strip()
        try:
            version = parse_version(entry.get('version'), f'<sdf> of {shown}') \
                if entry.get('version') is not None else (0, 0)
        except ValueError as error:
            raise UriRefused(str(error)) from None
        if name and version <= NEWEST_VERSION:
            candidates.append((version, -len(candidates), name))
    if not candidates:
        raise UriRefused(f'{shown} names no <sdf> file of version {NEWEST_VERSION[0]}.'
                         f'{NEWEST_VERSION[1]} or older')
    name = max(candidates)[2]
    path = os.path.realpath(os.path.join(folder, name))
    if os.path.isabs(name) or not within(path, folder):
        raise UriRefused(f'{shown} names {quoted(name)}, which is not in its folder')
    return path


class SdfPaths:
    """The roots an SDF file's uris may lead into, and where each uri leads."""

    def __init__(self, package_resolver, environ=None):
        """Resolve packages with package_resolver; resource folders from environ (os's)."""
        environ = os.environ if environ is None else environ
        self.package_resolver = package_resolver
        folders = []
        for variable in RESOURCE_PATH_VARIABLES:
            for folder in environ.get(variable, '').split(os.pathsep):
                if folder and os.path.isabs(folder) and os.path.isdir(folder):
                    folders.append(os.path.realpath(folder))
        self.resource_folders = tuple(dict.fromkeys(folders))
        self._model_folders = None

    def model_folders(self):
        """Return the folders model://<name> is looked for in, in order."""
        if self._model_folders is None:
            packages = [os.path.join(share, MODELS_FOLDER)
                        for share in installed_shares_of(self.package_resolver).values()]
            self._model_folders = self.resource_folders + tuple(
                os.path.realpath(folder) for folder in packages if os.path.isdir(folder))
        return self._model_folders

    def root_of(self, base_dir):
        """Return the root a file in base_dir may name files in."""
        share = share_holding(base_dir, self.package_resolver)
        if share is not None:
            return share
        for folder in self.resource_folders:
            if within(base_dir, folder):
                return folder
        return base_dir

    def locate(self, uri, base_dir, what):
        """
        Return the real path a uri names (a file or a folder) inside the roots.

        base_dir: the real folder of the file that names it (None: a text, which names files by
        model://, package:// or an absolute path alone); what names the uri in the messages.
        Raise UriRefused for a uri that may not be read, UriMissing for one that names nothing.
        """
        shown = f'{what} {quoted(uri)}'
        base_dir = os.path.realpath(base_dir) if base_dir else None
        if len(uri) > MAX_URI_LENGTH or '\0' in uri or not uri.strip():
            raise UriRefused(f'{shown} is no uri')
        scheme, separator, rest = uri.partition('://')
        if not separator:
            scheme, rest = '', uri
        if scheme == 'model':
            candidate = self._in_model_folders(rest, shown)
        elif scheme == 'package':
            candidate = self._in_package(rest, shown)
        elif scheme == 'file' or (not scheme and os.path.isabs(rest)):
            if not os.path.isabs(rest):
                raise UriRefused(f'{shown} is a file:// uri without an absolute path')
            candidate = rest
        elif not scheme:
            if base_dir is None:
                raise UriMissing(shown, 'a relative path, but the SDF came as text, which '
                                 'names files by model://, package:// or absolute path')
            candidate = os.path.join(base_dir, rest)
        elif scheme in ('http', 'https', 'ftp', 'ftps'):
            raise UriRefused(f'{shown} is on the network, where the world never goes; of Fuel '
                             "only OpenRobotics' 'Ground Plane' and 'Sun' are built in")
        else:
            raise UriRefused(f'{shown} has the scheme {quoted(scheme)}; SDF here names files '
                             'by model://, package://, file:// or a path')
        path = os.path.realpath(candidate)
        roots = list(self.resource_folders)
        if base_dir is not None:
            roots.append(self.root_of(base_dir))
        if not any(within(path, root) for root in roots) and \
                share_holding(path, self.package_resolver) is None:
            raise UriRefused(f'{shown} leads outside the folders SDF files may name files in '
                             '(the resource paths, the installed packages, the root of the '
                             'file naming it)')
        if not os.path.exists(path):
            raise UriMissing(shown, f'nothing is there ({quoted(path)})')
        return path

    def _in_model_folders(self, rest, shown):
        name, _, inside = rest.partition('/')
        if not name or name in ('.', '..'):
            raise UriRefused(f'{shown} names no model')
        for folder in self.model_folders():
            if os.path.isdir(os.path.join(folder, name)):
                return os.path.join(folder, name, inside)
        variables = ', '.join(RESOURCE_PATH_VARIABLES)
        raise UriMissing(shown, f'no model {quoted(name)} in the folders of {variables} or in '
                         'the models/ folder of an installed package')

    def _in_package(self, rest, shown):
        package, _, inside = rest.partition('/')
        if not package or package in ('.', '..'):
            raise UriRefused(f'{shown} names no package')
        try:
            share = self.package_resolver(package) if self.package_resolver else None
        except Exception:  # ament's PackageNotFoundError, or a resolver's own error
            share = None
        if share and os.path.isdir(share):
            return os.path.join(share, inside)
        for folder in self.resource_folders:
            if os.path.isdir(os.path.join(folder, package)):
                return os.path.join(folder, package, inside)
        raise UriMissing(shown, f'package {quoted(package)} is not installed')
