"""
The simulated world: ground, light, gravity and the robots spawned into it.

World is the only owner of the MuJoCo spec, model and data. Robots are attached to the live
spec and the model is recompiled in place, so spawning or deleting one robot leaves the state
of every other robot exactly as it was.
"""

import collections
from dataclasses import dataclass
import logging
import math
import os

import mujoco
import numpy as np

from service_tutorial import urdf_loader
from service_tutorial.diff_drive import body_velocity
from service_tutorial.diff_drive import EncoderOdometry
from service_tutorial.diff_drive import ODOMETRY_SOURCE_ENCODER
from service_tutorial.diff_drive import wheel_speeds

_logger = logging.getLogger('service_tutorial.world')

WORLD_FRAMES = ('', 'world')
SCOPE_SEPARATOR = '::'
MAX_MODEL_NAME_LENGTH = 64
# Leaves room for the topic names under it within the DDS limit of about 250 characters.
MAX_NAMESPACE_LENGTH = 200
# Longest piece of a caller's text repeated in a refusal.
MAX_QUOTED_LENGTH = 80
# Fastest a diff drive turns a wheel's rim, in m/s; faster commands are scaled down to it.
MAX_WHEEL_RIM_SPEED = 10.0
# Beyond these magnitudes a model's state is treated as broken, like MuJoCo's own checks.
HUGE_POSITION = 1e8
HUGE_VELOCITY = 1e5
HUGE_ACCELERATION = 1e10
_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_BAD_STATE_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                       mujoco.mjtWarning.mjWARN_BADQACC)
_IDENTITY_QUATERNION = (1.0, 0.0, 0.0, 0.0)
# What a model's integration state is made of, in MjData, carried over when the spec is rebuilt.
_STATE_FIELDS = ('qpos', 'qvel', 'qacc_warmstart', 'qfrc_applied', 'act', 'ctrl')


class WorldError(ValueError):
    """A request the world refuses; str(error) names the cause and the offending value."""


@dataclass(frozen=True, eq=False)
class ModelState:
    """Pose and twist of a model's base link, expressed in a reference frame."""

    position: np.ndarray          # (3,) metres
    orientation: np.ndarray       # (4,) unit quaternion (w, x, y, z), MuJoCo order
    linear_velocity: np.ndarray   # (3,) m/s
    angular_velocity: np.ndarray  # (3,) rad/s


@dataclass(frozen=True, eq=False)
class Odometry:
    """Odometry of a diff-drive robot: pose in the odometry frame, twist in the base frame."""

    position: np.ndarray          # (3,) metres, in odometry_frame
    orientation: np.ndarray       # (4,) unit quaternion (w, x, y, z), in odometry_frame
    linear_velocity: np.ndarray   # (3,) m/s, in robot_base_frame
    angular_velocity: np.ndarray  # (3,) rad/s, in robot_base_frame
    odometry_frame: str
    robot_base_frame: str


def _log_mujoco_warning(message):
    _logger.warning('MuJoCo: %s', message)


def _route_mujoco_messages():
    """Send MuJoCo warnings to logging; never let MuJoCo write MUJOCO_LOG.TXT."""
    mujoco.set_mju_user_warning(_log_mujoco_warning)
    config = mujoco.MjLogConfig.get()
    config.logto_file = False
    config.set()


def _default_package_resolver():
    try:
        from ament_index_python.packages import get_package_share_directory
    except ImportError:
        return None
    return get_package_share_directory


def _vector(values, size, what):
    try:
        array = np.array(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise WorldError(f'{what} is not a vector of {size} numbers: {values!r}') from None
    if array.shape != (size,):
        raise WorldError(f'{what} must have {size} elements, not {array.size}')
    if not np.isfinite(array).all():
        raise WorldError(f'{what} contains NaN or infinity: {array.tolist()}')
    return array


def _unit_quaternion(values, what='orientation'):
    quaternion = _vector(values, 4, what)
    largest = np.abs(quaternion).max()
    if largest == 0.0:
        raise WorldError(f'{what} quaternion is zero: {quaternion.tolist()}')
    # Scaled first, so that neither huge nor tiny components overflow or underflow the norm.
    quaternion = quaternion / largest
    return quaternion / np.linalg.norm(quaternion)


def _position(values, what='position'):
    position = _vector(values, 3, what)
    if np.abs(position).max() >= HUGE_POSITION:
        raise WorldError(f'{what} must stay below {HUGE_POSITION:g} m in magnitude: '
                         f'{position.tolist()}')
    return position


def _finite_number(value, what):
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise WorldError(f'{what} is not a number: {value!r}') from None
    if not math.isfinite(number):
        raise WorldError(f'{what} is NaN or infinite: {number}')
    return number


def _take_steps(model, data, count=1):
    """Step the physics; return False if MuJoCo gave up on a step, out of memory for one."""
    try:
        mujoco.mj_step(model, data, count)
    except mujoco.FatalError as error:
        _logger.warning('MuJoCo: %s', str(error).splitlines()[0])
        return False
    return True


def _bounded(array, limit):
    """Return True if every value is finite and smaller than limit in magnitude."""
    return array.size == 0 or float(np.abs(array).max()) < limit


def _rotate(quaternion, vector):
    result = np.zeros(3)
    mujoco.mju_rotVecQuat(result, np.asarray(vector, float), np.asarray(quaternion, float))
    return result


def _rotate_back(quaternion, vector):
    inverse = np.zeros(4)
    mujoco.mju_negQuat(inverse, np.asarray(quaternion, float))
    return _rotate(inverse, vector)


def _multiply(first, second):
    result = np.zeros(4)
    mujoco.mju_mulQuat(result, np.asarray(first, float), np.asarray(second, float))
    return result


def _relative_quaternion(reference, quaternion):
    inverse = np.zeros(4)
    mujoco.mju_negQuat(inverse, np.asarray(reference, float))
    return _multiply(inverse, quaternion)


def _quoted(text):
    """Return user text in quotes for a message: control characters escaped, long text cut."""
    shown = text[:MAX_QUOTED_LENGTH]
    shown = ''.join(character if character.isprintable() else repr(character)[1:-1]
                    for character in shown)
    if len(text) > MAX_QUOTED_LENGTH:
        return f"'{shown}...' ({len(text)} characters)"
    return f"'{shown}'"


def _check_model_name(name):
    if not isinstance(name, str) or not name:
        raise WorldError('model name must not be empty')
    quoted = _quoted(name)
    if len(name) > MAX_MODEL_NAME_LENGTH:
        raise WorldError(f'model name {quoted} is longer than {MAX_MODEL_NAME_LENGTH} '
                         'characters')
    if SCOPE_SEPARATOR in name:
        raise WorldError(f"model name {quoted} must not contain '{SCOPE_SEPARATOR}'")
    if '/' in name:
        raise WorldError(f"model name {quoted} must not contain '/'")
    if any(character.isspace() for character in name):
        raise WorldError(f'model name {quoted} must not contain whitespace')
    if not name.isprintable() or any(character in '"\'<>&\\' for character in name):
        raise WorldError(f'model name {quoted} contains a character that is not allowed')
    if name in WORLD_FRAMES:
        raise WorldError(f'model name {quoted} is reserved for the world frame')


def _normalise_namespace(namespace):
    """Return a robot namespace as '' or '/a/b', or refuse what ROS would refuse."""
    namespace = (namespace or '').strip()
    tokens = [token for token in namespace.split('/') if token]
    for token in tokens:
        if not (token[0].isalpha() or token[0] == '_') or not all(
                character.isalnum() or character == '_' for character in token) or (
                not token.isascii()):
            raise WorldError(f'robot namespace {_quoted(namespace)} is not a valid ROS '
                             f'namespace: its part {_quoted(token)} must start with a letter '
                             'or underscore and hold only ASCII letters, digits and '
                             'underscores')
    normalised = '/' + '/'.join(tokens) if tokens else ''
    if len(normalised) > MAX_NAMESPACE_LENGTH:
        raise WorldError(f'robot namespace {_quoted(namespace)} is longer than '
                         f'{MAX_NAMESPACE_LENGTH} characters')
    return normalised


class _Drive:
    """Run-time state of one robot's diff drive."""

    def __init__(self, config, wheel_count):
        self.config = config
        self.acceleration = config.max_wheel_acceleration / config.wheel_radius  # rad/s^2
        self.targets = np.zeros(wheel_count)
        self.ramp_end = np.full(wheel_count, math.inf)
        self.expiry = math.inf
        self.encoder = EncoderOdometry(config.wheel_separation, config.wheel_radius)
        self.origin_position = np.zeros(3)
        self.origin_orientation = np.array(_IDENTITY_QUATERNION)
        # Indices into the compiled model, refreshed after every recompile.
        self.actuator_ids = np.zeros(wheel_count, dtype=int)
        self.act_adr = np.zeros(wheel_count, dtype=int)
        self.base_body_id = 0
        self.left_qpos_adr = self.right_qpos_adr = 0
        self.left_dof_adr = self.right_dof_adr = 0

    def next_event(self):
        return min(self.expiry, float(self.ramp_end.min()))


class _SpawnedModel:
    """What the world keeps about one spawned robot."""

    def __init__(self, name, namespace, description, frame, root):
        self.name = name
        self.namespace = namespace
        self.description = description
        self.frame = frame
        self.root = root
        self.spawn_position = np.array(frame.pos)
        self.spawn_orientation = np.array(frame.quat)
        self.drive = None
        # When the world last placed it (spawn, set state, reset), and whether the world has
        # since put it back at its spawn pose because it became unstable.
        self.placed = 0
        self.recovered = False
        if description.diff_drive is not None:
            config = description.diff_drive
            self.drive = _Drive(config, len(config.left_joints) + len(config.right_joints))
        # Indices into the compiled model, refreshed after every recompile.
        self.root_id = 0
        self.qpos_index = np.zeros(0, dtype=int)
        self.dof_index = np.zeros(0, dtype=int)
        self.act_index = np.zeros(0, dtype=int)
        self.actuator_index = np.zeros(0, dtype=int)
        self.free_qpos_adr = None
        self.free_dof_adr = None
        self.joint_qpos_adr = np.zeros(0, dtype=int)
        self.joint_dof_adr = np.zeros(0, dtype=int)

    def scoped(self, element_name):
        return self.name + SCOPE_SEPARATOR + element_name


class World:
    """A MuJoCo world with a ground plane into which URDF robots are spawned and deleted."""

    def __init__(self, *, timestep=0.002, gravity=(0.0, 0.0, -9.81), cmd_vel_timeout=0.5,
                 package_resolver=None):
        """Create an empty world; package_resolver maps a package name to its share folder."""
        timestep = _finite_number(timestep, 'timestep')
        if timestep <= 0.0:
            raise WorldError(f'timestep must be positive: {timestep}')
        gravity = _vector(gravity, 3, 'gravity')
        cmd_vel_timeout = _finite_number(cmd_vel_timeout, 'cmd_vel_timeout')
        if cmd_vel_timeout < 0.0:
            raise WorldError(f'cmd_vel_timeout must not be negative: {cmd_vel_timeout}')
        _route_mujoco_messages()
        self._timestep = timestep
        self._cmd_vel_timeout = cmd_vel_timeout
        self._package_resolver = (package_resolver if package_resolver is not None
                                  else _default_package_resolver())
        self._paused = False
        self._models = {}
        self._removed = []
        self._placements = 0
        self._next_event = math.inf
        self._kinematics_fresh = False
        self._gravity = gravity
        self._spec = self._make_spec()
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)
        self._resize_buffers()
        self._forward()

    def _make_spec(self):
        spec = mujoco.MjSpec()
        spec.modelname = 'service_tutorial'
        spec.compiler.degree = False
        spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
        option = spec.option
        option.timestep = self._timestep
        option.gravity = self._gravity
        # Velocity servos on light wheels need the implicit damping term to stay stable.
        option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        option.impratio = 10.0
        # MuJoCo's automatic reset would reset every robot; the world resets only the
        # robot that went unstable, see _recover().
        option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
        texture = spec.add_texture(
            name='ground_grid', type=mujoco.mjtTexture.mjTEXTURE_2D,
            builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, mark=mujoco.mjtMark.mjMARK_EDGE,
            rgb1=[0.25, 0.27, 0.3], rgb2=[0.32, 0.34, 0.37], markrgb=[0.6, 0.6, 0.6],
            width=256, height=256)
        material = spec.add_material(name='ground_grid', texrepeat=[1.0, 1.0],
                                     texuniform=True, reflectance=0.1)
        material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = texture.name
        spec.add_texture(
            name='sky', type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
            builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, rgb1=[0.55, 0.68, 0.82],
            rgb2=[0.1, 0.12, 0.15], width=256, height=1536)
        # A plane collides everywhere; its size only sets how far the floor is drawn.
        spec.worldbody.add_geom(
            name='ground_plane', type=mujoco.mjtGeom.mjGEOM_PLANE, size=[25.0, 25.0, 0.05],
            material='ground_grid', friction=[1.0, 0.005, 0.0001],
            solref=[urdf_loader.CONTACT_TIME_CONSTANT, 1.0])
        spec.worldbody.add_light(
            name='sun', type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0.0, 0.0, 10.0],
            dir=[0.3, 0.2, -1.0], diffuse=[0.7, 0.7, 0.7], specular=[0.2, 0.2, 0.2],
            castshadow=False)
        return spec

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
    def paused(self):
        """Return True while physics is paused."""
        return self._paused

    def model_names(self):
        """Return the names of the spawned models, in spawn order."""
        return list(self._models)

    def take_removed_models(self):
        """Return the models the world removed by itself because they kept blowing up."""
        removed, self._removed = self._removed, []
        return removed

    def has_model(self, name):
        """Return True if a model of that name exists."""
        return name in self._models

    def namespace(self, name):
        """Return the ROS namespace the model was spawned with ('' or '/a/b')."""
        return self._record(name).namespace

    def diff_drive_models(self):
        """Return the names of the models that carry a diff drive."""
        return [name for name, record in self._models.items() if record.drive is not None]

    def diff_drive(self, name):
        """Return the DiffDriveConfig of a model's diff drive."""
        return self._drive_record(name).drive.config

    def _record(self, name):
        record = self._models.get(name) if isinstance(name, str) else None
        if record is None:
            raise WorldError(f'no model named {_quoted(str(name))}')
        return record

    def _drive_record(self, name):
        record = self._record(name)
        if record.drive is None:
            raise WorldError(f"model '{name}' has no diff drive")
        return record

    # ---------------------------------------------------------------- spawn and delete

    def spawn_urdf(self, name, urdf_xml, *, position=(0.0, 0.0, 0.0),
                   orientation=_IDENTITY_QUATERNION, reference_frame='', namespace='',
                   base_dir=None):
        """Add a robot from URDF text; a refused request leaves the world unchanged."""
        _check_model_name(name)
        if name in self._models:
            raise WorldError(f'a model named {_quoted(name)} already exists')
        namespace = _normalise_namespace(namespace)
        position = _position(position)
        orientation = _unit_quaternion(orientation)
        frame_position, frame_orientation, _, _ = self._frame_state(reference_frame)
        world_position = frame_position + _rotate(frame_orientation, position)
        world_orientation = _multiply(frame_orientation, orientation)
        try:
            description = urdf_loader.load_urdf(
                urdf_xml, base_dir=base_dir, package_resolver=self._package_resolver,
                timestep=self._timestep)
        except urdf_loader.UrdfError as error:
            raise WorldError(str(error)) from None
        if description.anchored:
            world_position = world_position + _rotate(world_orientation,
                                                      description.root_position)
            world_orientation = _multiply(world_orientation, description.root_orientation)

        # MuJoCo carries positions, velocities and controls over a recompile, not the rest.
        saved = self._saved_state(self._models)
        try:
            frame, root = self._attach(self._spec, name, description, world_position,
                                       world_orientation)
            model, data = self._spec.recompile(self._model, self._data)
        except Exception as error:
            # The live spec still holds the half-attached robot: build it afresh without it.
            self._rebuild(self._models)
            reason = '; '.join(line.strip() for line in str(error).splitlines() if line.strip())
            reason = reason[len('Error: '):] if reason.startswith('Error: ') else reason
            raise WorldError(f"model '{name}' does not compile: {reason}") from None
        self._model, self._data = model, data
        record = _SpawnedModel(name, namespace, description, frame, root)
        self._models[name] = record
        self._mark_placed(record)
        self._after_recompile()
        self._restore_state(saved)
        failure = self._forward()
        if failure is not None:
            self._rebuild({other: kept for other, kept in self._models.items() if other != name})
            raise WorldError(f"model '{name}' cannot be simulated at {world_position.tolist()}: "
                             f'{failure}; does it overlap other models?')
        if record.drive is not None:
            self._restart_odometry(record)
        _logger.info("spawned model '%s' at %s", name, np.round(world_position, 4).tolist())

    def spawn_urdf_file(self, name, path, **kwargs):
        """Add a robot from a URDF file; relative mesh paths resolve against its folder."""
        try:
            with open(path, 'rb') as urdf_file:
                urdf_xml = urdf_file.read(urdf_loader.MAX_MODEL_XML_BYTES + 1)
        except OSError as error:
            raise WorldError(f"cannot read URDF file '{path}': {error.strerror}") from None
        kwargs.setdefault('base_dir', os.path.dirname(os.path.abspath(path)))
        self.spawn_urdf(name, urdf_xml, **kwargs)

    def delete_model(self, name):
        """Remove a model; every other model keeps its state."""
        self._record(name)
        self._rebuild({other: record for other, record in self._models.items() if other != name})
        _logger.info("deleted model '%s'", name)

    @staticmethod
    def _attach(spec, name, description, position, orientation):
        """Attach a robot's spec to a world spec under the name prefix; return frame and root."""
        frame = spec.worldbody.add_frame(pos=position, quat=orientation)
        # Attaching renames the robot's own spec too; a copy keeps the description as loaded.
        root = frame.attach_body(description.spec.copy().worldbody.first_body(),
                                 name + SCOPE_SEPARATOR, '')
        return frame, root

    def _rebuild(self, models):
        """
        Build the spec, model and data afresh, holding just the given models.

        A spec keeps a copy of every robot ever attached to it, deleted or not, so deleting
        from the live spec would make a long-running world grow without bound. A fresh spec
        holds only the live robots; their integration state is carried over, so the
        simulation goes on exactly as if the spec had been edited in place.
        """
        spec = self._make_spec()
        attached = {name: self._attach(spec, name, record.description, record.frame.pos,
                                       record.frame.quat)
                    for name, record in models.items()}
        model = spec.compile()
        data = mujoco.MjData(model)
        data.time = self._data.time
        saved = self._saved_state(models)
        self._spec, self._model, self._data, self._models = spec, model, data, models
        for record in models.values():
            record.frame, record.root = attached[record.name]
        self._after_recompile()
        self._restore_state(saved)
        self._forward()

    @staticmethod
    def _state_indices(record):
        """Return the indices of a model's entries in the arrays named by _STATE_FIELDS."""
        return (record.qpos_index, record.dof_index, record.dof_index, record.dof_index,
                record.act_index, record.actuator_index)

    def _saved_state(self, models):
        """Return a copy of each model's share of the integration state, by model name."""
        data = self._data
        return {name: [getattr(data, field)[index].copy() for field, index in
                       zip(_STATE_FIELDS, self._state_indices(record))]
                for name, record in models.items()}

    def _restore_state(self, saved):
        """Write saved shares of the integration state back, at the models' current places."""
        data = self._data
        for name, values in saved.items():
            for field, index, value in zip(_STATE_FIELDS,
                                           self._state_indices(self._models[name]), values):
                getattr(data, field)[index] = value
        self._kinematics_fresh = False

    def _mark_placed(self, record):
        """Note that a model was just put somewhere on purpose, not by a recovery."""
        self._placements += 1
        record.placed = self._placements
        record.recovered = False

    def _after_recompile(self):
        self._kinematics_fresh = False
        self._resize_buffers()
        for record in self._models.values():
            self._index_model(record)
        self._schedule_events()

    def _forward(self):
        """
        Compute what follows from the state; return why MuJoCo could not, or None.

        If MuJoCo could not, the next step fails the same way and its recovery sorts it out.
        """
        self._kinematics_fresh = False
        try:
            mujoco.mj_forward(self._model, self._data)
        except mujoco.FatalError as error:
            reason = str(error).splitlines()[0]
            _logger.warning('MuJoCo: %s', reason)
            return reason
        return None

    def _resize_buffers(self):
        size = mujoco.mj_stateSize(self._model, _STATE)
        self._chunk_start_state = np.empty(size)
        self._step_start_state = np.empty(size)

    def _index_model(self, record):
        model = self._model
        description = record.description

        def body_id(link):
            return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, record.scoped(link))

        body_ids = np.array([body_id(link) for link in description.links])
        record.root_id = body_id(description.root_link)
        joint_ids = np.nonzero(np.isin(model.jnt_bodyid, body_ids))[0]
        qpos, dofs = [], []
        for joint_id in joint_ids:
            kind = model.jnt_type[joint_id]
            width = {int(mujoco.mjtJoint.mjJNT_FREE): (7, 6),
                     int(mujoco.mjtJoint.mjJNT_BALL): (4, 3)}.get(int(kind), (1, 1))
            qpos.extend(range(model.jnt_qposadr[joint_id], model.jnt_qposadr[joint_id] + width[0]))
            dofs.extend(range(model.jnt_dofadr[joint_id], model.jnt_dofadr[joint_id] + width[1]))
            if kind == mujoco.mjtJoint.mjJNT_FREE:
                record.free_qpos_adr = int(model.jnt_qposadr[joint_id])
                record.free_dof_adr = int(model.jnt_dofadr[joint_id])
        record.qpos_index = np.array(qpos, dtype=int)
        record.dof_index = np.array(dofs, dtype=int)
        named_joints = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, record.scoped(j))
                        for j in description.joints]
        record.joint_qpos_adr = np.array([model.jnt_qposadr[j] for j in named_joints], int)
        record.joint_dof_adr = np.array([model.jnt_dofadr[j] for j in named_joints], int)
        drive = record.drive
        if drive is None:
            return
        config = drive.config
        drive.actuator_ids = np.array([
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR,
                              record.scoped(urdf_loader.drive_actuator_name(joint)))
            for joint in config.left_joints + config.right_joints], dtype=int)
        drive.act_adr = model.actuator_actadr[drive.actuator_ids].astype(int)
        record.actuator_index = drive.actuator_ids
        record.act_index = drive.act_adr
        base_link = config.robot_base_frame
        if base_link not in description.links:
            base_link = description.root_link
        drive.base_body_id = body_id(base_link)
        for side, joint in (('left', config.left_joint), ('right', config.right_joint)):
            joint_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, record.scoped(joint))
            setattr(drive, side + '_qpos_adr', int(model.jnt_qposadr[joint_id]))
            setattr(drive, side + '_dof_adr', int(model.jnt_dofadr[joint_id]))

    # ---------------------------------------------------------------- stepping

    def pause(self):
        """Stop physics: step() takes no steps until physics is resumed."""
        self._paused = True

    def unpause(self):
        """Let physics run again."""
        self._paused = False

    def step(self, count=1):
        """Advance count physics steps unless paused; return the number of steps taken."""
        count = int(count)
        if count < 0:
            raise WorldError(f'step count must not be negative: {count}')
        if self._paused or count == 0:
            return 0
        remaining = count
        while remaining > 0:
            # Re-read every chunk: recovering from an instability may rebuild model and data.
            model, data = self._model, self._data
            chunk = remaining
            if self._next_event < math.inf:
                steps_to_event = math.ceil((self._next_event - data.time) / self._timestep - 1e-6)
                chunk = min(chunk, max(1, steps_to_event))
            mujoco.mj_getState(model, data, self._chunk_start_state, _STATE)
            completed = _take_steps(model, data, chunk)
            remaining -= chunk
            if not (completed and self._state_is_sane()):
                self._recover(chunk)
            if self._data.time >= self._next_event - 0.5 * self._timestep:
                self._handle_drive_events()
        self._kinematics_fresh = False
        return count

    def _state_is_sane(self):
        data = self._data
        if any(data.warning[kind].number for kind in _BAD_STATE_WARNINGS):
            return False
        return (_bounded(data.qpos, HUGE_POSITION) and _bounded(data.qvel, HUGE_VELOCITY)
                and _bounded(data.qacc, HUGE_ACCELERATION)
                and _bounded(data.act, HUGE_VELOCITY))

    def _broken_models(self, check_acceleration=True):
        """
        Return the models whose state is not finite or huge.

        The acceleration is only meaningful right after a step, not after a state is restored.
        """
        data = self._data
        return [record for record in self._models.values()
                if not (_bounded(data.qpos[record.qpos_index], HUGE_POSITION)
                        and _bounded(data.qvel[record.dof_index], HUGE_VELOCITY)
                        and _bounded(data.act[record.act_index], HUGE_VELOCITY)
                        and (not check_acceleration
                             or _bounded(data.qacc[record.dof_index], HUGE_ACCELERATION)))]

    def _recover(self, chunk):
        """
        Replay the failed chunk from its start, one step at a time, sorting out each bad step.

        A robot that breaks a step is put back at its spawn pose at rest and the step is taken
        again; a robot that breaks a step again after that is removed from the world. The
        others go through the step as if nothing had happened.
        """
        mujoco.mj_setState(self._model, self._data, self._chunk_start_state, _STATE)
        self._clear_bad_state_warnings()
        # A state already broken at the start of the chunk was put there from outside.
        self._reset_models(self._broken_models(check_acceleration=False),
                           'was given NaN, infinity or a huge value')
        for _ in range(chunk):
            mujoco.mj_getState(self._model, self._data, self._step_start_state, _STATE)
            completed = _take_steps(self._model, self._data)
            # Every retake resets a robot for the first time or removes one, so this ends.
            for _ in range(2 * len(self._models) + 1):
                if completed and self._state_is_sane():
                    break
                culprit = self._culprit() if completed else self._crowded_model()
                if culprit is None:
                    self._reset_broken_state()
                    break
                completed = self._retake_step_without(culprit)
            else:
                self._reset_broken_state()
        self._clear_bad_state_warnings()

    def _culprit(self):
        """Return the model that most likely broke the last step, or None."""
        data = self._data
        broken = self._broken_models()
        # NaN spreads through the constraint solver to every robot in touch with the one it
        # came from, but the smooth (unconstrained) acceleration stays within that robot.
        smooth = [record for record in broken
                  if not _bounded(data.qacc_smooth[record.dof_index], HUGE_ACCELERATION)]
        # Failing that, the robot placed last, by a spawn or a set state, is the likeliest.
        return max(smooth or broken, key=lambda record: record.placed, default=None)

    def _crowded_model(self):
        """Return the model in most contacts in the step MuJoCo gave up on, or None."""
        model, data = self._model, self._data
        roots = {record.root_id: record for record in self._models.values()}
        geoms = np.asarray(data.contact.geom, dtype=int).reshape(-1)
        counts = collections.Counter(
            int(body) for body in model.body_rootid[model.geom_bodyid[geoms]] if body in roots)
        most = max(counts.values(), default=0)
        candidates = ([roots[body] for body, count in counts.items() if count == most]
                      or list(self._models.values()))
        return max(candidates, key=lambda record: record.placed, default=None)

    def _retake_step_without(self, culprit):
        """Undo the last step, reset or remove the culprit, and take the step again."""
        mujoco.mj_setState(self._model, self._data, self._step_start_state, _STATE)
        self._clear_bad_state_warnings()
        if culprit.recovered:
            _logger.error("model '%s' became unstable again after it was put back at its spawn "
                          'pose; it is removed from the world', culprit.name)
            self._rebuild({name: record for name, record in self._models.items()
                           if record is not culprit})
            self._removed.append(culprit.name)
        else:
            self._reset_models([culprit], 'became unstable')
            culprit.recovered = True
        # A further retake of this step starts from here, without the culprit's bad state.
        mujoco.mj_getState(self._model, self._data, self._step_start_state, _STATE)
        return _take_steps(self._model, self._data)

    def _clear_bad_state_warnings(self):
        for kind in _BAD_STATE_WARNINGS:
            self._data.warning[kind].number = 0

    def _reset_models(self, records, reason):
        data, model = self._data, self._model
        for record in records:
            _logger.warning("model '%s' %s; it is put back to its spawn pose at rest",
                            record.name, reason)
            data.qpos[record.qpos_index] = model.qpos0[record.qpos_index]
            data.qvel[record.dof_index] = 0.0
            data.qacc[record.dof_index] = 0.0
            data.qacc_warmstart[record.dof_index] = 0.0
            if record.drive is not None:
                self._stop_drive(record)
                self._restart_odometry(record)
        if records:
            self._kinematics_fresh = False
            self._schedule_events()

    def _reset_broken_state(self):
        """Reset the whole data, keeping the state of every robot that is still sound."""
        model, data = self._model, self._data
        _logger.warning('the simulation state is broken; resetting it, keeping the robots '
                        'whose state is sound')
        broken = {record.name for record in self._broken_models()}
        time = data.time
        kept = {name: (data.qpos[record.qpos_index].copy(), data.qvel[record.dof_index].copy(),
                       data.act[record.act_index].copy(), data.ctrl[record.actuator_index].copy())
                for name, record in self._models.items() if name not in broken}
        mujoco.mj_resetData(model, data)
        data.time = time
        for name, record in self._models.items():
            if name in kept:
                qpos, qvel, act, ctrl = kept[name]
                data.qpos[record.qpos_index] = qpos
                data.qvel[record.dof_index] = qvel
                data.act[record.act_index] = act
                data.ctrl[record.actuator_index] = ctrl
            elif record.drive is not None:
                _logger.warning("model '%s' is put back to its spawn pose at rest", name)
                self._stop_drive(record)
                self._restart_odometry(record)
        self._forward()
        self._schedule_events()

    # ---------------------------------------------------------------- resets

    def reset_simulation(self):
        """Put time to zero and every model back to its spawn pose at rest."""
        self._reset(keep_time=False)

    def reset_world(self):
        """Put every model back to its spawn pose at rest; time goes on."""
        self._reset(keep_time=True)

    def _reset(self, keep_time):
        model, data = self._model, self._data
        time = data.time
        mujoco.mj_resetData(model, data)
        if keep_time:
            data.time = time
        for record in self._models.values():
            self._mark_placed(record)
            if record.free_qpos_adr is None:
                self._place_anchored(record, record.spawn_position, record.spawn_orientation)
        self._forward()
        self._kinematics_fresh = False
        for record in self._models.values():
            if record.drive is not None:
                self._stop_drive(record)
                self._restart_odometry(record)
        self._schedule_events()

    # ---------------------------------------------------------------- frames and state

    def _refresh_kinematics(self):
        if not self._kinematics_fresh:
            mujoco.mj_kinematics(self._model, self._data)
            mujoco.mj_comPos(self._model, self._data)
            mujoco.mj_comVel(self._model, self._data)
            self._kinematics_fresh = True

    def _body_state(self, body_id):
        """Return position, orientation, linear and angular velocity of a body, in world."""
        self._refresh_kinematics()
        data = self._data
        twist = np.zeros(6)
        if body_id > 0:
            mujoco.mj_objectVelocity(self._model, data, mujoco.mjtObj.mjOBJ_BODY, body_id,
                                     twist, 0)
        return (data.xpos[body_id].copy(), data.xquat[body_id].copy(), twist[3:], twist[:3])

    def _frame_body(self, reference_frame):
        if not isinstance(reference_frame, str):
            raise WorldError(f'unknown reference frame {reference_frame!r}')
        if reference_frame in WORLD_FRAMES:
            return 0
        if reference_frame in self._models:
            return self._models[reference_frame].root_id
        model_name, separator, link = reference_frame.partition(SCOPE_SEPARATOR)
        if separator and model_name in self._models and link:
            body_id = mujoco.mj_name2id(self._model, mujoco.mjtObj.mjOBJ_BODY, reference_frame)
            if body_id > 0:
                return body_id
        raise WorldError(f'unknown reference frame {_quoted(reference_frame)}')

    def _frame_state(self, reference_frame):
        return self._body_state(self._frame_body(reference_frame))

    def get_model_state(self, name, reference_frame=''):
        """
        Return the pose and twist of a model's base link relative to reference_frame.

        The twist is the difference of the two frames' velocities, expressed in the reference
        frame, as gazebo_ros reports it.
        """
        record = self._record(name)
        frame_position, frame_orientation, frame_linear, frame_angular = (
            self._frame_state(reference_frame))
        position, orientation, linear, angular = self._body_state(record.root_id)
        return ModelState(
            position=_rotate_back(frame_orientation, position - frame_position),
            orientation=_relative_quaternion(frame_orientation, orientation),
            linear_velocity=_rotate_back(frame_orientation, linear - frame_linear),
            angular_velocity=_rotate_back(frame_orientation, angular - frame_angular))

    def set_model_state(self, name, *, position, orientation, linear_velocity=(0.0, 0.0, 0.0),
                        angular_velocity=(0.0, 0.0, 0.0), reference_frame=''):
        """Move a model's base link to a pose and twist given in reference_frame."""
        record = self._record(name)
        position = _position(position)
        orientation = _unit_quaternion(orientation)
        linear_velocity = _vector(linear_velocity, 3, 'linear_velocity')
        angular_velocity = _vector(angular_velocity, 3, 'angular_velocity')
        for what, velocity in (('linear_velocity', linear_velocity),
                               ('angular_velocity', angular_velocity)):
            if np.abs(velocity).max() >= HUGE_VELOCITY:
                raise WorldError(f'{what} of model {name!r} must stay below {HUGE_VELOCITY:g} '
                                 f'in magnitude: {velocity.tolist()}')
        frame_position, frame_orientation, frame_linear, frame_angular = (
            self._frame_state(reference_frame))
        world_position = frame_position + _rotate(frame_orientation, position)
        world_orientation = _multiply(frame_orientation, orientation)
        world_linear = frame_linear + _rotate(frame_orientation, linear_velocity)
        world_angular = frame_angular + _rotate(frame_orientation, angular_velocity)
        if record.free_qpos_adr is None:
            if np.any(linear_velocity) or np.any(angular_velocity):
                raise WorldError(f"model '{name}' is anchored to the world; it cannot be given "
                                 'a velocity')
            self._place_anchored(record, world_position, world_orientation)
        else:
            qpos, dof = record.free_qpos_adr, record.free_dof_adr
            data = self._data
            data.qpos[qpos:qpos + 3] = world_position
            data.qpos[qpos + 3:qpos + 7] = world_orientation
            # A free joint's angular velocity is expressed in the body frame.
            data.qvel[dof:dof + 3] = world_linear
            data.qvel[dof + 3:dof + 6] = _rotate_back(world_orientation, world_angular)
            data.qacc_warmstart[record.dof_index] = 0.0
        self._mark_placed(record)
        self._kinematics_fresh = False

    def _place_anchored(self, record, position, orientation):
        """Move a model that has no free joint, in the compiled model and in the spec."""
        self._model.body_pos[record.root_id] = position
        self._model.body_quat[record.root_id] = orientation
        record.frame.pos = position
        record.frame.quat = orientation
        self._kinematics_fresh = False

    def joint_state(self, name):
        """Return (URDF joint names, positions, velocities) of a model's moving joints."""
        record = self._record(name)
        return (list(record.description.joints),
                self._data.qpos[record.joint_qpos_adr].copy(),
                self._data.qvel[record.joint_dof_adr].copy())

    # ---------------------------------------------------------------- diff drive

    def command_velocity(self, name, linear_x, angular_z):
        """
        Command a diff-drive robot's body twist; it lapses after cmd_vel_timeout seconds.

        A command that would turn a wheel rim faster than MAX_WHEEL_RIM_SPEED is scaled down
        to that speed, keeping the radius of the turn. Return the (linear_x, angular_z) that
        is carried out.
        """
        record = self._drive_record(name)
        linear_x = _finite_number(linear_x, 'linear_x')
        angular_z = _finite_number(angular_z, 'angular_z')
        drive = record.drive
        config = drive.config
        # Scale before the wheel speeds are worked out, so that no sum of huge values overflows.
        fastest_rim = max(abs(linear_x), abs(angular_z) * config.wheel_separation / 2.0)
        if fastest_rim > MAX_WHEEL_RIM_SPEED:
            scale = MAX_WHEEL_RIM_SPEED / fastest_rim
            linear_x, angular_z = linear_x * scale, angular_z * scale
        left, right = wheel_speeds(linear_x, angular_z, config.wheel_separation,
                                   config.wheel_radius)
        fastest_wheel = max(abs(left), abs(right)) * config.wheel_radius
        if fastest_wheel > MAX_WHEEL_RIM_SPEED:
            scale = MAX_WHEEL_RIM_SPEED / fastest_wheel
            linear_x, angular_z = linear_x * scale, angular_z * scale
            left, right = left * scale, right * scale
        self._update_encoder_odometry(record)
        self._set_wheel_targets(record, left, right)
        drive.expiry = (self._data.time + self._cmd_vel_timeout if self._cmd_vel_timeout > 0.0
                        else math.inf)
        self._schedule_events()
        return linear_x, angular_z

    def _set_wheel_targets(self, record, left, right):
        """
        Set wheel speed set points, ramped at the drive's acceleration limit if it has one.

        The servo's activation is its speed set point and its control is the set point's rate
        of change, so a ramp needs no work between its start and its end.
        """
        drive, data = record.drive, self._data
        half = len(drive.targets) // 2
        drive.targets[:half] = left
        drive.targets[half:] = right
        for index, (actuator, act) in enumerate(zip(drive.actuator_ids, drive.act_adr)):
            change = drive.targets[index] - data.act[act]
            ramp_steps = (math.floor(abs(change) / (drive.acceleration * self._timestep))
                          if drive.acceleration > 0.0 else 0)
            if ramp_steps == 0:
                data.act[act] = drive.targets[index]
                data.ctrl[actuator] = 0.0
                drive.ramp_end[index] = math.inf
            else:
                data.ctrl[actuator] = math.copysign(drive.acceleration, change)
                drive.ramp_end[index] = data.time + ramp_steps * self._timestep

    def _stop_drive(self, record):
        drive, data = record.drive, self._data
        drive.targets[:] = 0.0
        drive.ramp_end[:] = math.inf
        drive.expiry = math.inf
        data.act[drive.act_adr] = 0.0
        data.ctrl[drive.actuator_ids] = 0.0

    def _schedule_events(self):
        self._next_event = min((record.drive.next_event() for record in self._models.values()
                                if record.drive is not None), default=math.inf)

    def _handle_drive_events(self):
        data = self._data
        now = data.time + 0.5 * self._timestep
        for record in self._models.values():
            drive = record.drive
            if drive is None or drive.next_event() > now:
                continue
            for index in np.nonzero(drive.ramp_end <= now)[0]:
                data.act[drive.act_adr[index]] = drive.targets[index]
                data.ctrl[drive.actuator_ids[index]] = 0.0
                drive.ramp_end[index] = math.inf
            if drive.expiry <= now:
                self._update_encoder_odometry(record)
                self._set_wheel_targets(record, 0.0, 0.0)
                drive.expiry = math.inf
        self._schedule_events()

    def _update_encoder_odometry(self, record):
        drive, qpos = record.drive, self._data.qpos
        drive.encoder.update(qpos[drive.left_qpos_adr], qpos[drive.right_qpos_adr])

    def _restart_odometry(self, record):
        drive, qpos = record.drive, self._data.qpos
        drive.encoder.reset(qpos[drive.left_qpos_adr], qpos[drive.right_qpos_adr])
        position, orientation, _, _ = self._body_state(drive.base_body_id)
        drive.origin_position = position
        drive.origin_orientation = orientation

    def odometry(self, name):
        """Return the odometry of a diff-drive robot, from its encoders or ground truth."""
        record = self._drive_record(name)
        drive = record.drive
        config = drive.config
        if config.odometry_source == ODOMETRY_SOURCE_ENCODER:
            self._update_encoder_odometry(record)
            encoder = drive.encoder
            qvel = self._data.qvel
            linear_x, angular_z = body_velocity(
                qvel[drive.left_dof_adr], qvel[drive.right_dof_adr], config.wheel_separation,
                config.wheel_radius)
            return Odometry(
                position=np.array([encoder.x, encoder.y, 0.0]),
                orientation=np.array([math.cos(encoder.yaw / 2.0), 0.0, 0.0,
                                      math.sin(encoder.yaw / 2.0)]),
                linear_velocity=np.array([linear_x, 0.0, 0.0]),
                angular_velocity=np.array([0.0, 0.0, angular_z]),
                odometry_frame=config.odometry_frame,
                robot_base_frame=config.robot_base_frame)
        position, orientation, linear, angular = self._body_state(drive.base_body_id)
        return Odometry(
            position=_rotate_back(drive.origin_orientation, position - drive.origin_position),
            orientation=_relative_quaternion(drive.origin_orientation, orientation),
            linear_velocity=_rotate_back(orientation, linear),
            angular_velocity=_rotate_back(orientation, angular),
            odometry_frame=config.odometry_frame,
            robot_base_frame=config.robot_base_frame)
