"""
The standard's worlds: LoadWorld, UnloadWorld, GetCurrentWorld and GetAvailableWorlds.

A world is a world file (sim/world_files.py) in the worlds/ folder of this or any installed
package, found by its uri, or given as text: this package's own (.world.xml) or Gazebo's (SDF,
.world or .sdf), whose static models are its scenery and whose other models its entities, with its
own timestep and gravity; a URDF or MJCF scenery file alone loads too, as a world with that scenery
and nothing else. Every world is on this machine, so offline_only changes nothing. Where the
standard leaves a choice:
- A load removes every entity, loads the world, spawns its models and leaves it STOPPED at time 0.
  It is all or nothing (world_loader.py): a load that fails leaves the previous world, or the
  no-world state, exactly as it was, and says which with the standard's code.
- fail_on_unsupported_element refuses a world file with elements this world does not know (106);
  without it they are ignored and named in the answer's message.
- The scenery's missing meshes are left out and named (ignore_missing_or_unsupported_assets or
  not), and so is an SDF world's moving model whose every collision is a missing mesh (it would
  fall for ever); the elements an SDF world holds and the world does not simulate (sensors,
  gz-sim's model plugins, Gazebo Classic's <state>) are unsupported elements as above; a model or
  scenery file the world names that is not there is MISSING_ASSETS (104), a scenery with moving
  joints or plugins UNSUPPORTED_ASSETS (105), one that does not compile a parse error (103).
- GetAvailableWorlds lists the world files of every package's worlds/ and of additional_sources
  (folders inside a package's share, as package:// or file:// uris). A world file that does not
  read is a failed source: DEFAULT_SOURCES_FAILED (101) with the others listed, or OK with the
  failures named when continue_on_error is set; a refused additional source is named likewise.
"""

import os

from service_tutorial.sim.package_files import confined_path, package_uri, PackageFileError
from service_tutorial.sim.validation import quoted, Reason, WorldError
from service_tutorial.sim.world_files import parse_world, read_world_file
from service_tutorial.sim.world_files import SDF_WORLD_SUFFIXES, WORLD_SUFFIXES
from service_tutorial.world_node.answers import LOAD_WORLD_CODES, Refusal, standard_answer
from service_tutorial.world_node.packages import installed_shares
from service_tutorial.world_node.standard.entity_filters import tags_test
from service_tutorial.world_node.world_loader import LoadedWorld, WORLDS_FOLDER
from simulation_interfaces.msg import Resource, Result, SimulatorFeatures, WorldResource
from simulation_interfaces.srv import GetAvailableWorlds, GetCurrentWorld, LoadWorld
from simulation_interfaces.srv import UnloadWorld

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
        self.load_world_srv = node.serve(
            LoadWorld, 'load_world', self.load_world_callback)
        self.unload_world_srv = node.serve(
            UnloadWorld, 'unload_world', self.unload_world_callback)
        self.get_current_world_srv = node.serve(
            GetCurrentWorld, 'get_current_world', self.get_current_world_callback)
        self.get_available_worlds_srv = node.serve(
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
            prepared = self.loader.prepare(loaded)
            self.loader.load(prepared)
            self.simulation.stopped = True
            self.node.after_reset()
            fill_world(response.world, loaded)
            self.node.get_logger().info(f'LoadWorld: loaded world {quoted(loaded.world.name)}')
            meshes, models = prepared.left_out()
            said = [f'ignored: {", ".join(ignored[:10])}' + _more(ignored, 10)] if ignored \
                else []
            if meshes:
                said.append(f'meshes not found, left out: {", ".join(meshes[:10])}'
                            + _more(meshes, 10))
            if models:
                said.append('models left out, as nothing of them collides without their '
                            f'missing meshes: {", ".join(map(quoted, models[:10]))}'
                            + _more(models, 10))
            for note in prepared.scenery.notes if prepared.scenery else ():
                self.node.get_logger().warning(f'LoadWorld: {note}')
            return '; '.join(said)
        before = self.loader.current
        note = standard_answer(self.node, 'LoadWorld', response.result,
                               self.node.holding_time(load), LOAD_WORLD_CODES)
        if note:
            response.result.error_message = note
        elif response.result.result != Result.RESULT_OK:
            kept = 'the no-world state is kept' if before is None else \
                f'world {quoted(before.world.name)} is kept as it was'
            response.result.error_message += f'; {kept}'
        return response

    def _read(self, uri, resource_string):
        """Return the LoadedWorld a request names, read but not yet tried."""
        if uri:
            try:
                path = confined_path(uri, self.package_share)
            except PackageFileError as error:
                raise WorldError(str(error), Reason.NO_RESOURCE) from None
            return LoadedWorld(read_world_file(path, self.package_share, shown=uri,
                                               scenery_alone=True), uri)
        if not resource_string:
            raise Refusal(LoadWorld.Response.NO_RESOURCE,
                          'neither uri nor resource_string is given')
        return LoadedWorld(parse_world(resource_string, 'resource_string', None,
                                       self.package_share, scenery_alone=True),
                           '', resource_string=resource_string)

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
        standard_answer(self.node, 'UnloadWorld', response.result, self.node.holding_time(unload))
        return response

    def get_current_world_callback(self, request, response):
        """Say which world is loaded, or NO_WORLD_LOADED."""
        def current():
            if self.loader.current is None:
                raise Refusal(GetCurrentWorld.Response.NO_WORLD_LOADED, 'no world is loaded')
            fill_world(response.world, self.loader.current)
        standard_answer(self.node, 'GetCurrentWorld', response.result, current)
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
        message = standard_answer(self.node, 'GetAvailableWorlds', response.result, available)
        if message:
            response.result.error_message = message
        return response

    def _default_folders(self):
        """Return (folder, failure) of the worlds/ folder of every installed package."""
        folders = [os.path.join(share, WORLDS_FOLDER) for share in installed_shares().values()]
        return [(folder, None) for folder in folders if os.path.isdir(folder)]

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
                           if name.endswith(WORLD_SUFFIXES))[:MAX_WORLD_FILES]
            for name in names:
                path = os.path.realpath(os.path.join(folder, name))
                uri = package_uri(path, self.package_share)
                if uri is None or not os.path.isfile(path):
                    failures.append(f'{quoted(os.path.join(folder, name))} leads outside its '
                                    'package')
                    continue
                try:
                    world = read_world_file(path, self.package_share, shown=uri, listing=True)
                except WorldError as error:
                    if not (name.endswith(SDF_WORLD_SUFFIXES)
                            and error.reason == Reason.UNSUPPORTED_FORMAT):
                        failures.append(str(error))
                    continue  # an SDF model beside the worlds is no world
                resource = WorldResource()
                fill_world(resource, LoadedWorld(world, uri))
                resources.append(resource)
        return resources, failures


def _more(items, shown):
    """Say how many items more there are than the shown first ones, or ''."""
    return f' (and {len(items) - shown} more)' if len(items) > shown else ''


def fill_world(message, loaded):
    """Fill a WorldResource with what a LoadedWorld says."""
    world = loaded.world
    message.name = world.name
    message.world_resource = Resource(uri=loaded.uri, resource_string=loaded.resource_string)
    message.description = world.description
    message.tags = list(world.tags)
