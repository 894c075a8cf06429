"""
The standard's worlds: LoadWorld, UnloadWorld, GetCurrentWorld and GetAvailableWorlds.

A world is a world file (sim/world_files.py) in the worlds/ folder of this or any installed
package, found by its uri, or given as text; a URDF or MJCF scenery file alone loads too, as a
world with that scenery and nothing else. Every world is on this machine, so offline_only
changes nothing. Where the standard leaves a choice:
- A load removes every entity, loads the world, spawns its models and leaves it STOPPED at time
  0. It is all or nothing (world_loader.py): a load that fails leaves the previous world, or the
  no-world state, exactly as it was, and says which with the standard's code.
- fail_on_unsupported_element refuses a world file with elements this world does not know
  (106); without it they are ignored and named in the answer's message.
- The scenery's missing meshes are left out and named (ignore_missing_or_unsupported_assets or
  not); a model or scenery file the world names that is not there is MISSING_ASSETS (104), a
  scenery with moving joints or plugins UNSUPPORTED_ASSETS (105), one that does not compile a
  parse error (103).
- GetAvailableWorlds lists the world files of every package's worlds/ and of additional_sources
  (folders inside a package's share, as package:// or file:// uris). A world file that does not
  read is a failed source: DEFAULT_SOURCES_FAILED (101) with the others listed, or OK with the
  failures named when continue_on_error is set; a refused additional source is named likewise.
"""

import os

from ament_index_python.packages import get_packages_with_prefixes
from service_tutorial.sim.package_files import confined_path, package_uri, PackageFileError
from service_tutorial.sim.scenery import SceneryError
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES, parse_xml
from service_tutorial.sim.validation import quoted, WorldError
from service_tutorial.sim.world_files import NO_RESOURCE, PARSE_ERROR, parse_world
from service_tutorial.sim.world_files import read_world_file, UNSUPPORTED_FORMAT
from service_tutorial.sim.world_files import WORLD_FILE_SUFFIX, WorldFile, WorldFileError
from service_tutorial.world_node.standard.entity_filters import tags_test
from service_tutorial.world_node.standard.results import answer, Refusal
from service_tutorial.world_node.world_loader import LoadedWorld, MISSING_ASSETS
from service_tutorial.world_node.world_loader import MODEL_REFUSED, WORLDS_FOLDER
from simulation_interfaces.msg import Resource, Result, SimulatorFeatures, WorldResource
from simulation_interfaces.srv import GetAvailableWorlds, GetCurrentWorld, LoadWorld
from simulation_interfaces.srv import UnloadWorld

CODES = {
    UNSUPPORTED_FORMAT: LoadWorld.Response.UNSUPPORTED_FORMAT,
    NO_RESOURCE: LoadWorld.Response.NO_RESOURCE,
    PARSE_ERROR: LoadWorld.Response.RESOURCE_PARSE_ERROR,
    MISSING_ASSETS: LoadWorld.Response.MISSING_ASSETS,
    MODEL_REFUSED: Result.RESULT_OPERATION_FAILED,
}
# Scenery files load as worlds of their own; other simulators' formats are named.
SCENERY_ROOTS = ('robot', 'mujoco')
OTHER_FORMATS = {'sdf': 'SDF', 'gazebo': 'SDF'}
MAX_SOURCES = 100
MAX_WORLD_FILES = 1000  # of one folder


class WorldServices:
    """The standard's world services of the world node (node.MujocoWorld)."""

    FEATURES = (SimulatorFeatures.WORLD_LOADING, SimulatorFeatures.WORLD_RESOURCE_STRING,
                SimulatorFeatures.WORLD_TAGS, SimulatorFeatures.WORLD_UNLOADING,
                SimulatorFeatures.WORLD_INFO_GETTING, SimulatorFeatures.AVAILABLE_WORLDS)

    def __init__(self, node, simulation, package_share):
        """Serve node's worlds; simulation (SimulationServices) keeps the STOPPED state."""
        self.node = node
        self.simulation = simulation
        self.package_share = package_share
        self.loader = node.world_loader
        self.load_world_srv = node.create_service(
            LoadWorld, 'load_world', self.load_world_callback)
        self.unload_world_srv = node.create_service(
            UnloadWorld, 'unload_world', self.unload_world_callback)
        self.get_current_world_srv = node.create_service(
            GetCurrentWorld, 'get_current_world', self.get_current_world_callback)
        self.get_available_worlds_srv = node.create_service(
            GetAvailableWorlds, 'get_available_worlds', self.get_available_worlds_callback)

    def load_world_callback(self, request, response):
        """Replace the world by the one at uri (or in resource_string); leave it STOPPED."""
        def load():
            loaded = self._read(request.uri, request.resource_string)
            ignored = loaded.world.unsupported
            if ignored and request.fail_on_unsupported_element:
                raise Refusal(LoadWorld.Response.UNSUPPORTED_ELEMENTS,
                              f'world {quoted(loaded.world.name)} has elements this world does '
                              f'not support: {", ".join(ignored[:10])}')
            prepared = self._prepared(loaded)
            self.loader.load(prepared)
            self.simulation.stopped = True
            self.node.after_reset()
            fill_world(response.world, loaded)
            self.node.get_logger().info(f'LoadWorld: loaded world {quoted(loaded.world.name)}')
            return f'ignored: {", ".join(ignored[:10])}' if ignored else ''
        before = self.loader.current
        note = answer(self.node, 'LoadWorld', response.result, self.node.holding_time(load))
        if note:
            response.result.error_message = note
        elif response.result.result != Result.RESULT_OK:
            kept = 'the no-world state is kept' if before is None else \
                f'world {quoted(before.world.name)} is kept as it was'
            response.result.error_message += f'; {kept}'
        return response

    def _read(self, uri, resource_string):
        """Return the LoadedWorld a request names, read but not yet tried."""
        try:
            if uri:
                return self._read_file(uri)
            if not resource_string:
                raise Refusal(LoadWorld.Response.NO_RESOURCE,
                              'neither uri nor resource_string is given')
            return self._read_text(resource_string)
        except WorldFileError as error:
            raise Refusal(CODES[error.kind], str(error)) from None

    def _read_file(self, uri):
        try:
            path = confined_path(uri, self.package_share)
        except PackageFileError as error:
            raise WorldFileError(NO_RESOURCE, str(error)) from None
        root_tag = _root_tag(path, quoted(uri))
        if root_tag in SCENERY_ROOTS:
            name = os.path.splitext(os.path.basename(path))[0]
            world = WorldFile(name=name, description=f'the scenery {quoted(uri)} alone',
                              tags=(), scenery=path, models=())
        else:
            _check_format(root_tag, quoted(uri))
            world = read_world_file(path, self.package_share, shown=uri)
        return LoadedWorld(world, uri)

    def _read_text(self, text):
        what = 'resource_string'
        root_tag = _root_tag(None, what, text=text)
        if root_tag in SCENERY_ROOTS:
            world = WorldFile(name='scenery', description='a scenery given as text', tags=(),
                              scenery='', models=())
            return LoadedWorld(world, '', resource_string=text, scenery_text=text)
        _check_format(root_tag, what)
        return LoadedWorld(parse_world(text, what, None, self.package_share), '',
                           resource_string=text)

    def _prepared(self, loaded):
        """Read and try a world's scenery and models, mapping the refusals to codes."""
        try:
            return self.loader.prepare(loaded)
        except SceneryError as error:
            code = LoadWorld.Response.UNSUPPORTED_ASSETS if error.unsupported else \
                LoadWorld.Response.RESOURCE_PARSE_ERROR
            raise Refusal(code, str(error)) from None
        except WorldFileError as error:
            raise Refusal(CODES[error.kind], str(error)) from None

    def unload_world_callback(self, request, response):
        """Remove every entity and the world: the no-world state, where nothing steps."""
        def unload():
            if self.loader.current is None:
                raise Refusal(UnloadWorld.Response.NO_WORLD_LOADED, 'no world is loaded')
            name = self.loader.current.world.name if self.loader.current else 'the world'
            self.loader.unload()
            self.simulation.stopped = False
            self.node.after_reset()
            self.node.get_logger().info(f'UnloadWorld: unloaded {quoted(name)}')
        answer(self.node, 'UnloadWorld', response.result, self.node.holding_time(unload))
        return response

    def get_current_world_callback(self, request, response):
        """Say which world is loaded, or NO_WORLD_LOADED."""
        def current():
            if self.loader.current is None:
                raise Refusal(GetCurrentWorld.Response.NO_WORLD_LOADED, 'no world is loaded')
            fill_world(response.world, self.loader.current)
        answer(self.node, 'GetCurrentWorld', response.result, current)
        return response

    def get_available_worlds_callback(self, request, response):
        """List the world files of every package's worlds/ and of additional_sources."""
        def available():
            matches = tags_test(request.filter)
            if len(request.additional_sources) > MAX_SOURCES:
                raise Refusal(Result.RESULT_OPERATION_FAILED, f'{len(request.additional_sources)} '
                              f'sources are more than {MAX_SOURCES}')
            found, default_failures = self._scan(self._default_folders())
            extra, extra_failures = self._scan(self._source_folders(request.additional_sources))
            worlds = {resource.world_resource.uri: resource for resource in found + extra}
            response.worlds = [world for world in worlds.values()
                               if matches is None or matches(set(world.tags))]
            failures = default_failures + extra_failures
            message = '; '.join(failures[:10]) + (
                f' (and {len(failures) - 10} more)' if len(failures) > 10 else '')
            if default_failures and not request.continue_on_error:
                raise Refusal(GetAvailableWorlds.Response.DEFAULT_SOURCES_FAILED, message)
            if extra_failures and not request.continue_on_error:
                raise Refusal(Result.RESULT_OPERATION_FAILED, message)
            return message
        message = answer(self.node, 'GetAvailableWorlds', response.result, available)
        if message:
            response.result.error_message = message
        return response

    def _default_folders(self):
        """Return (folder, failure) of the worlds/ folder of every installed package."""
        folders = []
        for package in sorted(get_packages_with_prefixes()):
            try:
                folder = os.path.join(self.package_share(package), WORLDS_FOLDER)
            except Exception:  # noqa: B902 a package the index names but cannot place
                continue
            if os.path.isdir(folder):
                folders.append((folder, None))
        return folders

    def _source_folders(self, sources):
        folders = []
        for source in sources:
            try:
                folders.append((confined_path(source, self.package_share, folder=True,
                                              what='source'), None))
            except PackageFileError as error:
                folders.append((None, str(error)))
        return folders

    def _scan(self, folders):
        """Return the WorldResources of the world files in folders, and what failed."""
        resources, failures = [], []
        for folder, failure in folders:
            if failure is not None:
                failures.append(failure)
                continue
            names = sorted(name for name in os.listdir(folder)
                           if name.endswith(WORLD_FILE_SUFFIX))[:MAX_WORLD_FILES]
            for name in names:
                path = os.path.realpath(os.path.join(folder, name))
                uri = package_uri(path, self.package_share)
                if uri is None or not os.path.isfile(path):
                    failures.append(f'{quoted(os.path.join(folder, name))} leads outside its '
                                    'package')
                    continue
                try:
                    world = read_world_file(path, self.package_share, shown=uri)
                except WorldError as error:
                    failures.append(str(error))
                    continue
                resource = WorldResource()
                fill_world(resource, LoadedWorld(world, uri))
                resources.append(resource)
        return resources, failures


def fill_world(message, loaded):
    """Fill a WorldResource with what a LoadedWorld says."""
    world = loaded.world
    message.name = world.name
    message.world_resource = Resource(uri=loaded.uri, resource_string=loaded.resource_string)
    message.description = world.description
    message.tags = list(world.tags)


def _root_tag(path, what, *, text=None):
    """Return the root element's name of a world or scenery file (or text), or refuse it."""
    try:
        if text is None:
            with open(path, 'rb') as world_file:
                data = world_file.read(MAX_MODEL_XML_BYTES + 1)
        else:
            data = text.encode('utf-8')
        if len(data) > MAX_MODEL_XML_BYTES:
            raise WorldFileError(PARSE_ERROR, f'{what} is larger than {MAX_MODEL_XML_BYTES} '
                                 'bytes')
        root = parse_xml(data, what)
    except OSError as error:
        raise WorldFileError(NO_RESOURCE, f'{what} cannot be read: {error.strerror}') from None
    except ValueError as error:  # the parser's UrdfError
        raise WorldFileError(PARSE_ERROR, str(error)) from None
    return root.tag if isinstance(root.tag, str) else ''


def _check_format(tag, what):
    if tag in OTHER_FORMATS:
        raise WorldFileError(UNSUPPORTED_FORMAT, f'{what} is {OTHER_FORMATS[tag]} (root element '
                             f'<{tag}>); this world loads world files (<world>), URDF and MJCF')
    if tag != 'world':
        raise WorldFileError(UNSUPPORTED_FORMAT, f'{what} is no world file: its root element is '
                             f'<{tag[:40]}>, not <world>')
