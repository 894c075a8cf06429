"""
Which world the node serves: its scenery, start-up models and named poses, and loading another.

A world comes from a world file (sim/world_files.py): this package's worlds/ and every installed
package's worlds/ hold them, found by name (<name>.world.xml, or Gazebo's <name>.world and
<name>.sdf). A world whose file says its physics (an SDF world's <physics> and <gravity>) runs with
them; any other with the node's timestep parameter and the Earth's gravity. Loading one is all or
nothing: the new scenery, its models and their files are read and tried in a trial world first
(World.trial), and only if all of them hold does the node remove every entity with its topics, load
the scenery and spawn the world's models. A load that fails leaves the world the node had exactly
as it was. A scenery is read once while its file is unchanged, and the same scenery with the same
spawn orders is tried once: loading a world again costs little more than building it. Unloading
leaves the no-world state: no entities, nothing steps or spawns until a load.
"""

from dataclasses import dataclass, replace
import logging
import os

from rclpy.parameter import Parameter
from service_tutorial.sim import frames
from service_tutorial.sim.core_logs import core_logger
from service_tutorial.sim.package_files import confined_path, PackageFileError
from service_tutorial.sim.robot_files import file_model_name, read_path
from service_tutorial.sim.scene import EARTH_GRAVITY
from service_tutorial.sim.scenery import Scenery, SceneryError
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.validation import quoted, Reason, WorldError
from service_tutorial.sim.world import World, WORLD_LOG
from service_tutorial.sim.world_files import read_world_file, StartModel
from service_tutorial.sim.world_files import WORLD_SUFFIXES, WorldFileError
from service_tutorial.world_node.packages import installed_shares, own_share, PACKAGE
from service_tutorial.world_node.parameters import ParameterError
from service_tutorial.world_node.ros_names import normalise_namespace

WORLDS_FOLDER = 'worlds'
# The world parameters that, set to anything but their default, replace the world's own.
SCENERY_PARAMETER = 'scenery'
MODEL_PARAMETERS = ('models', 'model_names', 'model_namespaces', 'model_poses')
KEPT_SCENERIES = 8  # the sceneries of the last worlds loaded, kept read and checked
# A trial world's spawns are not the world's: it says only what goes wrong.
TRIAL_LOG = WORLD_LOG + '.trial'


def resolve_model_path(model):
    """Find a model (URDF or xacro) or scenery file: an absolute path, or one in models/."""
    if os.path.isabs(model):
        return model
    return os.path.join(own_share(), 'models', model)


def parameter_models(parameters):
    """Return (file, name, namespace, position, orientation) of each model the parameters name."""
    files = list(parameters['models'])
    names = list(parameters['model_names']) or [file_model_name(f) for f in files]
    namespaces = list(parameters['model_namespaces']) or [''] * len(files)
    poses = list(parameters['model_poses']) or [0.0] * 4 * len(files)
    if not len(files) == len(names) == len(namespaces) == len(poses) // 4:
        raise ValueError('models, model_names, model_namespaces and model_poses '
                         '(4 numbers each) must describe the same number of models')
    return [(resolve_model_path(model), name, namespace, poses[4 * index:4 * index + 3],
             frames.yaw_quaternion(poses[4 * index + 3]))
            for index, (model, name, namespace) in enumerate(zip(files, names, namespaces))]


@dataclass(frozen=True)
class LoadedWorld:
    """The world a node serves: what its file says and where the file is ('' for a text)."""

    world: object  # a WorldFile
    uri: str
    resource_string: str = ''


@dataclass(frozen=True)
class PreparedWorld:
    """A world read and tried, ready to replace the current one without a failure."""

    loaded: LoadedWorld
    scenery: object  # a Scenery, or None for the bare plane
    orders: tuple  # SpawnOrders of its models
    namespaces: tuple
    timestep: float  # s
    gravity: tuple  # m/s^2

    @property
    def place(self):
        """Return the world's name and where it lies on the Earth, as World.load() takes them."""
        world = self.loaded.world
        return {'name': world.name, 'spherical_coordinates': world.spherical_coordinates}

    def left_out(self):
        """Return what the world leaves out: (meshes not found, models with nothing to collide)."""
        return (self.scenery.missing_meshes if self.scenery else ()), self.loaded.world.left_out


class WorldLoader:
    """Loads worlds into a MujocoWorld node's World, keeping what the current one names."""

    def __init__(self, node, package_share):
        """Serve node's world; package_share finds a package's share folder."""
        self.node = node
        self.package_share = package_share
        self.current = None  # the LoadedWorld, None in the no-world state
        self.start_up_models = frozenset()  # the Models the current world spawned
        self._trial_world = None  # made at the first load, kept with the robots it built
        self._sceneries = {}  # real path -> (mtime, size, Scenery): a scenery is read once
        self._tried = frozenset()  # (Scenery, SpawnOrders) that spawned in the trial world
        node.parameters.refuse_when(self.refuse_playing)

    def refuse_playing(self, values):
        """Refuse paused:=false in the no-world state, whoever sets it (a parameter check)."""
        if not values['paused'] and self.current is None:
            return 'no world is loaded: load one (LoadWorld) before playing'
        return None

    @property
    def named_poses(self):
        """Return the current world's NamedPoses by name ({} with no world)."""
        return {} if self.current is None else self.current.world.named_poses

    def find(self, name):
        """Return the path of a world file by name: this package's worlds/ first, then any."""
        if '/' in name or name in ('.', '..'):
            raise WorldFileError(f'{quoted(name)} is no world name: give a name, a package:// '
                                 'uri or an absolute path', Reason.NO_RESOURCE)
        shares = [self.package_share(PACKAGE)] + list(installed_shares().values())
        for share in shares:
            for suffix in WORLD_SUFFIXES:
                path = os.path.join(share, WORLDS_FOLDER, name + suffix)
                if os.path.isfile(path):
                    return path
        raise WorldFileError(f'no world named {quoted(name)} in the worlds/ folder of any '
                             'installed package', Reason.NO_RESOURCE)

    def start_up_world(self, parameters, defaults):
        """
        Return the PreparedWorld the node starts with: the `world` parameter's file.

        '' is the no-world state (None). scenery, the models parameters and timestep, set to
        other than their defaults, replace what the file says. A world that cannot be read is a bad
        parameter: ParameterError.
        """
        try:
            loaded = self._start_up_file(parameters, defaults)
            return None if loaded is None else self.prepare(loaded, trial=False)
        except WorldError as error:
            raise ParameterError(f'parameter world:={quoted(parameters["world"])}: '
                                 f'{error}') from None

    def begin(self, start_up):
        """Spawn the start-up world's models into the node's new World, or unload it (None)."""
        if start_up is None:
            self.unload()
        else:
            self.populate(start_up)

    def _start_up_file(self, parameters, defaults):
        choice = parameters['world']
        if not choice:
            return None
        if '://' in choice:
            path, uri = path_of_uri(choice, self.package_share), choice
        elif os.path.isabs(choice):
            path, uri = choice, 'file://' + choice
        else:
            path = self.find(choice)
            uri = f'package://{os.path.basename(os.path.dirname(os.path.dirname(path)))}/' \
                f'{WORLDS_FOLDER}/{os.path.basename(path)}'
        world = read_world_file(path, self.package_share)
        replaced = []
        if world.physics and parameters['timestep'] != defaults['timestep']:
            world = replace(world, physics=(parameters['timestep'], world.physics[1]))
            replaced.append('timestep')
        if parameters[SCENERY_PARAMETER] != defaults[SCENERY_PARAMETER]:
            scenery = parameters[SCENERY_PARAMETER]
            world = replace(world, scenery=resolve_model_path(scenery) if scenery else '',
                            sdf_world=None)
            replaced.append('scenery')
        if any(parameters[name] != tuple(defaults[name]) for name in MODEL_PARAMETERS):
            world = replace(world, models=tuple(
                StartModel(name, path, namespace, tuple(position), tuple(orientation))
                for path, name, namespace, position, orientation
                in parameter_models(parameters)))
            replaced.append('models')
        if replaced:
            world = replace(world, description=f'{world.description} ({" and ".join(replaced)}'
                            ' from the parameters)')
        return LoadedWorld(world, uri)

    def prepare(self, loaded, *, trial=True):
        """
        Read a world's scenery and models; return a PreparedWorld or raise WorldError.

        trial: spawn the models in a trial world first (the node's world must exist), so that
        a world whose models cannot stand together is refused before anything changes.
        """
        world = loaded.world
        scenery = None
        if world.sdf_world is not None:
            scenery = Scenery.from_sdf(world.sdf_world, f'world {quoted(world.name)}',
                                       package_resolver=self.package_share)
        elif world.scenery_text:
            scenery = Scenery.from_text(world.scenery_text, 'resource_string',
                                        package_resolver=self.package_share)
        elif world.scenery:
            scenery = self._scenery(world.scenery)
        orders, namespaces = [], []
        for model in world.models:
            try:
                robot = model.source or read_path(model.path)
                namespaces.append(normalise_namespace(model.namespace))
            except WorldError as error:  # a file the world names and cannot have is an asset
                raise WorldFileError(str(error), Reason.MISSING_ASSET
                                     if error.reason == Reason.NO_RESOURCE else error.reason) \
                    from None
            orders.append(SpawnOrder.of(model.name or file_model_name(model.path), robot,
                                        position=model.position,
                                        orientation=model.orientation))
        timestep, gravity = world.physics or (self.node.parameters['timestep'], EARTH_GRAVITY)
        # The same files and poses spawn the same way in the same physics.
        tried = (scenery, tuple(orders), timestep, tuple(gravity))
        if trial and tried not in self._tried:
            refused = [(order.name, outcome) for order, outcome
                       in zip(orders, self._trial(scenery, orders, timestep, gravity))
                       if isinstance(outcome, WorldError)]
            if refused:
                name, error = refused[0]
                raise WorldFileError(f'world {quoted(world.name)} cannot spawn its model '
                                     f'{quoted(name)}: {error}', Reason.MODEL_REFUSED)
            self._tried = (self._tried | {tried}) if len(self._tried) < KEPT_SCENERIES \
                else {tried}
        return PreparedWorld(loaded, scenery, tuple(orders), tuple(namespaces), timestep,
                             tuple(gravity))

    def _scenery(self, path):
        """Return the Scenery of a file, read again only when the file changed."""
        try:
            stat = os.stat(path)
        except OSError as error:
            raise SceneryError(f'cannot read scenery file {quoted(path)}: {error.strerror}',
                               Reason.MISSING_ASSET) from None
        kept = self._sceneries.pop(path, None)
        if kept is None or kept[:2] != (stat.st_mtime_ns, stat.st_size):
            kept = (stat.st_mtime_ns, stat.st_size,
                    Scenery(path, package_resolver=self.package_share))
        self._sceneries[path] = kept  # the latest last
        while len(self._sceneries) > KEPT_SCENERIES:
            del self._sceneries[next(iter(self._sceneries))]
        return kept[2]

    def _trial(self, scenery, orders, timestep, gravity):
        """Return what spawning orders into a world with scenery gives, said quietly."""
        if self._trial_world is None:  # kept: it builds each robot file once
            trial_log = core_logger(TRIAL_LOG)
            trial_log.setLevel(logging.WARNING)
            self._trial_world = World(timestep=timestep, package_resolver=self.package_share,
                                      logger=trial_log)
        self._trial_world.load(scenery, timestep=timestep, gravity=gravity)
        return self._trial_world.spawn(orders)

    def load(self, prepared):
        """Replace the world: every entity goes, the prepared scenery and models come."""
        self._clear()
        self.node.world.load(prepared.scenery, timestep=prepared.timestep,
                             gravity=prepared.gravity, **prepared.place)
        self.node.viewer.reopen()
        self.populate(prepared)
        self._pause()

    def populate(self, prepared):
        """Spawn a prepared world's models into the loaded scenery; it is the current world."""
        node = self.node
        self.current = prepared.loaded
        outcomes = node.spawn_models(list(prepared.orders), list(prepared.namespaces))
        failed = [outcome for outcome in outcomes if isinstance(outcome, Exception)]
        self.start_up_models = frozenset(node.world.models.values())
        node.make_model_topics()
        if failed:  # the trial spawned them all: this is a bug, not the request's fault
            raise WorldError(f'world {quoted(prepared.loaded.world.name)} loaded, but '
                             f'{len(failed)} of its models failed: {failed[0]}')

    def unload(self):
        """Enter the no-world state: every entity and the scenery go; nothing steps."""
        self._clear()
        self.node.world.load(None, timestep=self.node.parameters['timestep'],
                             gravity=EARTH_GRAVITY)
        self.node.viewer.reopen()
        self.current = None
        self.start_up_models = frozenset()
        self._pause()

    def _pause(self):
        """Have the paused parameter say what the world is: paused, after a load or unload."""
        self.node.set_parameters([Parameter('paused', Parameter.Type.BOOL, True)])

    def check_loaded(self, what):
        """Refuse what (a spawn...) with WorldError in the no-world state."""
        if self.current is None:
            raise WorldError(f'no world is loaded: {what} waits for a world (LoadWorld)',
                             Reason.NO_WORLD)

    def _clear(self):
        """Stop any stepping and destroy every model's topics; World.load() drops the models."""
        node = self.node
        node.requested_steps.stop('the world is replaced')
        for name in node.world.model_names():
            node.forget_model(name)


def path_of_uri(uri, package_share):
    """Return the real path of a world file uri inside the roots, or raise WorldFileError."""
    try:
        return confined_path(uri, package_share)
    except PackageFileError as error:
        raise WorldFileError(str(error), Reason.NO_RESOURCE) from None
