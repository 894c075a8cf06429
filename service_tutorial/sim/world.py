"""
The simulated world: ground, light, gravity and the models spawned into it.

World is the only owner of the MuJoCo spec, model and data, and of the registry of models.
Models are attached to the live spec and the model is recompiled in place, so spawning or
deleting one model leaves the state of every other model exactly as it was.
"""

import dataclasses
import math
import types

import mujoco
from service_tutorial.sim import attachment
from service_tutorial.sim import frames
from service_tutorial.sim import plugins
from service_tutorial.sim import scene
from service_tutorial.sim import spawning
from service_tutorial.sim import validation
from service_tutorial.sim.background_renders import BackgroundRenders
from service_tutorial.sim.core_logs import core_logger
from service_tutorial.sim.description_cache import DescriptionCache
from service_tutorial.sim.model import Model
from service_tutorial.sim.plugins.gz_names import DEFAULT_WORLD_NAME
from service_tutorial.sim.recovery import Recovery
from service_tutorial.sim.recovery import take_steps
from service_tutorial.sim.scenery import Scenery
from service_tutorial.sim.validation import DescriptionError
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import Reason
from service_tutorial.sim.validation import WorldError

# The world's log: one name for everything that happens to its models.
WORLD_LOG = 'service_tutorial.world'
# MuJoCo's warnings are the process's: one log for them, whichever world they come from.
_mujoco_logger = core_logger(WORLD_LOG)


def _log_mujoco_warning(message):
    if not message.startswith(attachment.EMPTY_PREFIX_WARNING):
        _mujoco_logger.warning('MuJoCo: %s', message)


def _route_mujoco_messages():
    """Send MuJoCo warnings to logging; never let MuJoCo write MUJOCO_LOG.TXT."""
    mujoco.set_mju_user_warning(_log_mujoco_warning)
    config = mujoco.MjLogConfig.get()
    config.logto_file = False
    config.set()


def _physics(timestep, gravity):
    """Return a world's timestep and gravity, checked."""
    timestep = validation.finite_number(timestep, 'timestep')
    if timestep <= 0.0:
        raise WorldError(f'timestep must be positive: {timestep}')
    return timestep, validation.vector(gravity, 3, 'gravity')


class World:
    """
    A MuJoCo world with a ground plane into which robots are spawned and deleted.

    rebuild(), forward(), state_changed(), schedule_events(), schedule_event() and
    body_state() are there for the core's own pieces, recovery and plugins; nodes use the rest.
    """

    def __init__(self, *, timestep=0.002, gravity=scene.EARTH_GRAVITY, cmd_vel_timeout=0.5,
                 package_resolver=None, scenery=None, background_rendering=False, logger=None,
                 name=DEFAULT_WORLD_NAME, spherical_coordinates=None):
        """
        Create a world without models, with the static obstacles of a scenery file if given.

        scenery: a path or a Scenery; package_resolver maps a package to its share folder, for
        package:// meshes (none: refused); background_rendering draws cameras on a thread;
        logger: where the world says what happens to its models (core_logger(WORLD_LOG));
        name: what gz topics call the world; spherical_coordinates: where its origin lies on
        the Earth (a geodesy.SphericalCoordinates), None if nowhere.
        """
        timestep, gravity = _physics(timestep, gravity)
        cmd_vel_timeout = validation.non_negative_number(cmd_vel_timeout, 'cmd_vel_timeout')
        _route_mujoco_messages()
        self._logger = logger or core_logger(WORLD_LOG)
        self._timestep = timestep
        self._cmd_vel_timeout = cmd_vel_timeout
        self._paused = False
        self._name = name
        self._spherical_coordinates = spherical_coordinates
        self._models = {}
        self._package_resolver = package_resolver
        self._descriptions = DescriptionCache(package_resolver, timestep)
        self._next_event = math.inf
        self._kinematics_fresh = False
        if isinstance(scenery, str):
            scenery = Scenery(scenery, package_resolver=package_resolver) if scenery else None
        self._scene = scene.Scene(timestep, gravity, scenery)
        self._spec = self._scene.spec()
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)
        self._replaced = None  # the model and data the last recompile replaced, till released
        self._recovery = Recovery(self, self._logger)
        self.background_renders = BackgroundRenders() if background_rendering else None
        self.forward()

    # ---------------------------------------------------------------- accessors

    @property
    def model(self):
        """Return the compiled MjModel; re-read it after every spawn or delete."""
        return self._model

    @property
    def data(self):
        """Return the MjData; re-read it after every spawn or delete."""
        return self._data

    @property
    def time(self):
        """Return the simulation time in seconds."""
        return float(self._data.time)

    @property
    def timestep(self):
        """Return the physics timestep in seconds."""
        return self._timestep

    @property
    def cmd_vel_timeout(self):
        """Return how long a drive's velocity command lasts, in seconds (0: for ever)."""
        return self._cmd_vel_timeout

    @property
    def name(self):
        """Return the world's name, as gz topics name it."""
        return self._name

    @property
    def spherical_coordinates(self):
        """Return where the world's origin lies on the Earth, or None if it says nowhere."""
        return self._spherical_coordinates

    @property
    def paused(self):
        """Return True while physics is paused."""
        return self._paused

    @property
    def models(self):
        """Return the spawned models by name, in spawn order (a read-only mapping)."""
        return types.MappingProxyType(self._models)

    def model_names(self):
        """Return the names of the spawned models, in spawn order."""
        return list(self._models)

    def take_removed_models(self):
        """Return a recovery.Removal for each model the world removed since the last call."""
        return self._recovery.take_removed()

    def _spawned(self, name):
        model = self._models.get(name) if isinstance(name, str) else None
        if model is None:
            raise WorldError(f'no model named {quoted(str(name))}', Reason.NO_SUCH_MODEL)
        return model

    # ---------------------------------------------------------------- spawn and delete

    def spawn(self, orders):
        """
        Add the robots of SpawnOrders with one recompile; log where, and their notes.

        Return a Model or the WorldError that refused it, for each order in order. A refused
        order changes nothing and leaves the others to spawn. Should the batch not compile or
        not simulate as a whole, its models are attached one at a time to tell which fail.
        """
        outcomes, batch = spawning.prepared_batch(
            orders, taken=self._models, frame_state=self._frame_state,
            descriptions=self._descriptions)
        if batch and self._attach(batch) is not None:
            for name, model in batch.items():
                refusal = self._attach({name: model})
                if refusal is not None:
                    outcomes[outcomes.index(model)] = refusal
        spawned = [model for model in outcomes if isinstance(model, Model)]
        for model in spawned:
            model.reset_plugins()
        spawning.log_spawned(self._logger, spawned)
        # Only the new plugins can bring the next event closer: no pass over the whole fleet.
        self.schedule_event(plugins.next_event(spawned))
        return outcomes

    def _attach(self, batch):
        """Attach models with one recompile; return None, or the WorldError that undid it."""
        first = next(iter(batch.values()))  # named in the refusal, meant for a model alone
        for model in batch.values():
            model.frame = None  # a frame of a spec a failed attach threw away is gone
        try:
            self._replace(*attachment.attach(self._spec, self._model, self._data,
                                             batch.values()))
        except attachment.CompileError as error:
            # The live spec still holds the half-attached robots: build it afresh without them.
            self.rebuild(self._models)
            return DescriptionError(f"model '{first.name}' does not compile: {error}",
                                    Reason.DOES_NOT_COMPILE)
        self._models.update(batch)
        for model in batch.values():
            model.mark_placed()
        self._after_recompile(batch.values())  # the others' elements kept their ids
        failure = self.forward()
        if failure is not None:
            self.rebuild({name: kept for name, kept in self._models.items()
                          if name not in batch})
            return WorldError(f"model '{first.name}' cannot be simulated at "
                              f'{first.spawn_position.tolist()}: {failure}; does it overlap '
                              'other models?', Reason.CANNOT_SIMULATE)
        return None

    def delete_model(self, name):
        """Remove a model; every other model keeps its state."""
        model = self._spawned(name)
        names = list(self._models)
        del self._models[name]
        try:
            self._replace(*attachment.detach(self._spec, self._model, self._data, model))
        except attachment.CompileError:
            self.rebuild(self._models)
            return
        # The models spawned after it moved up in MuJoCo's arrays; the others stayed. The
        # next event stays: were it the deleted model's, one update() finds nothing due.
        self._after_recompile([self._models[later] for later in names[names.index(name) + 1:]])
        self.forward()
        self._logger.info("deleted model '%s'", name)

    def load(self, scenery, *, timestep=None, gravity=None, name=DEFAULT_WORLD_NAME,
             spherical_coordinates=None):
        """
        Take a new scenery (a Scenery or None) with no models, at time 0, and new physics.

        name and spherical_coordinates: the new world's, as the constructor takes them.
        """
        timestep, gravity = _physics(self._timestep if timestep is None else timestep,
                                     self._scene.gravity if gravity is None else gravity)
        self._name, self._spherical_coordinates = name, spherical_coordinates
        if timestep != self._timestep:  # robots are built for their world's timestep
            self._timestep = timestep
            self._descriptions = DescriptionCache(self._package_resolver, timestep)
        self._scene = dataclasses.replace(self._scene, scenery=scenery, timestep=timestep,
                                          gravity=tuple(gravity))
        self.rebuild({})
        self._reset(keep_time=False)

    def rebuild(self, models):
        """Build spec, model and data afresh with just the given models, their state kept."""
        saved = attachment.saved_state(models, self._data)
        self._spec, mj_model, data = attachment.build(self._scene.spec(), models)
        data.time = self._data.time
        self._replace(mj_model, data)
        self._models = models
        self._after_recompile(models.values())
        self.schedule_events()
        attachment.restore_state(models, data, saved)
        self.forward()

    def _replace(self, mj_model, data):
        # Freeing an MjData (its arena) takes 0.3 to 0.4 ms: the replaced pair waits for
        # release_replaced(), which a node calls between its ticks, after the answer.
        self._replaced = (self._model, self._data)
        self._model, self._data = mj_model, data

    def release_replaced(self):
        """Free the MuJoCo model and data the last recompile replaced, if not done yet."""
        self._replaced = None

    def _after_recompile(self, moved):
        # A new model and data; moved: the models whose elements may have new ids.
        self._kinematics_fresh = False
        self._recovery.resize()
        for model in moved:
            model.bind(self)

    def forward(self):
        """
        Compute what follows from the state; return why MuJoCo could not, or None.

        If MuJoCo could not, the next step fails the same way and its recovery sorts it out.
        """
        self._kinematics_fresh = False
        try:
            mujoco.mj_forward(self._model, self._data)
        except mujoco.FatalError as error:
            reason = str(error).splitlines()[0]
            self._logger.warning('MuJoCo: %s', reason)
            return reason
        self._kinematics_fresh = True  # mj_forward computed body_state()'s quantities too
        return None

    def state_changed(self):
        """Note that the state was written outside a step: positions must be computed again."""
        self._kinematics_fresh = False

    # ---------------------------------------------------------------- stepping

    def pause(self):
        """Stop physics: step() takes no steps until physics is resumed."""
        self._paused = True

    def unpause(self):
        """Let physics run again."""
        self._paused = False

    def step(self, count=1, *, even_if_paused=False):
        """Advance count physics steps unless paused or even_if_paused; return the steps taken."""
        count = int(count)
        if count < 0:
            raise WorldError(f'step count must not be negative: {count}')
        if (self._paused and not even_if_paused) or count == 0:
            return 0
        remaining = count
        while remaining > 0:
            # Re-read every chunk: recovering from an instability may rebuild model and data.
            model, data = self._model, self._data
            chunk = remaining
            if self._next_event < math.inf:
                steps_to_event = math.ceil((self._next_event - data.time) / self._timestep - 1e-6)
                chunk = min(chunk, max(1, steps_to_event))
            self._recovery.start_chunk()
            completed = take_steps(model, data, chunk, logger=self._logger)
            remaining -= chunk
            if not (completed and self._recovery.state_is_sane()):
                self._recovery.recover(chunk)
            if self._data.time >= self._next_event - 0.5 * self._timestep:
                self._update_plugins()
        self._kinematics_fresh = False
        return count

    def set_cmd_vel_timeout(self, seconds):
        """Let drive commands lapse after seconds (0: never), those in force as well."""
        self._cmd_vel_timeout = validation.non_negative_number(seconds, 'cmd_vel_timeout')
        plugins.set_command_timeout(self._models.values(), self._cmd_vel_timeout)
        self.schedule_events()

    def schedule_events(self):
        """Work out when a plugin next needs its update()."""
        self._next_event = plugins.next_event(self._models.values())

    def schedule_event(self, time):
        """Have plugins updated by simulation time `time` at the latest, rescanning none."""
        self._next_event = min(self._next_event, time)  # later: one update() finds nothing

    def _update_plugins(self):
        plugins.update_due(self._models.values(), self._data.time + 0.5 * self._timestep)
        self.schedule_events()

    # ---------------------------------------------------------------- resets

    def reset_simulation(self):
        """Put time to zero and every model back to its spawn pose at rest."""
        self._reset(keep_time=False)

    def reset_world(self):
        """Put every model back to its spawn pose at rest; time goes on."""
        self._reset(keep_time=True)

    def reset_time(self):
        """Put time back to zero, models as they are; plugins start again, drives uncommanded."""
        self._data.time = 0.0
        for model in self._models.values():
            model.reset_plugins()
        self.schedule_events()

    def _reset(self, keep_time):
        time = self._data.time
        mujoco.mj_resetData(self._model, self._data)
        if keep_time:
            self._data.time = time
        for model in self._models.values():
            model.return_to_spawn(self._model)
        self.forward()
        for model in self._models.values():
            model.reset_plugins()
        self.schedule_events()

    # ---------------------------------------------------------------- frames and state

    def body_state(self, body_id):
        """Return a body's pose and twist in the world frame, as a ModelState."""
        if not self._kinematics_fresh and body_id != 0:
            mujoco.mj_kinematics(self._model, self._data)
            mujoco.mj_comPos(self._model, self._data)
            mujoco.mj_comVel(self._model, self._data)
            self._kinematics_fresh = True
        return frames.body_state(self._model, self._data, body_id)

    def _frame_state(self, reference_frame):
        return self.body_state(frames.frame_body(reference_frame, self._models, self._model))

    def get_model_state(self, name, reference_frame=''):
        """
        Return the pose and twist of a model's base link relative to reference_frame.

        The twist is the difference of the two frames' velocities, expressed in the reference
        frame, as gazebo_ros reports it.
        """
        model = self._spawned(name)
        frame = self._frame_state(reference_frame)
        return frames.expressed_in(frame, self.body_state(model.root_id))

    def get_model_accelerations(self, names):
        """Return (linear, angular) acceleration of each model's base link in the world."""
        roots = [self._spawned(name).root_id for name in names]
        for root in roots[:1]:
            self.body_state(root)  # brings the kinematics up to date
        return frames.body_accelerations(self._model, self._data, roots)

    def set_model_state(self, name, *, position, orientation, linear_velocity=(0.0, 0.0, 0.0),
                        angular_velocity=(0.0, 0.0, 0.0), reference_frame=''):
        """Move a model's base link to a pose and twist given in reference_frame."""
        model = self._spawned(name)
        relative = model.checked_state(
            position=position, orientation=orientation, linear_velocity=linear_velocity,
            angular_velocity=angular_velocity)
        model.place(self._model, self._data,
                    frames.in_world(self._frame_state(reference_frame), relative))
        model.mark_placed()
        self._kinematics_fresh = False

    def joint_state(self, name):
        """Return (URDF joint names, positions, velocities) of a model's moving joints."""
        return self._spawned(name).joint_state(self._data)
