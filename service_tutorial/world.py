"""
The simulated world: ground, light, gravity and the robots spawned into it.

World is the only owner of the MuJoCo spec, model and data. Robots are attached to the live
spec and the model is recompiled in place, so spawning or deleting one robot leaves the state
of every other robot exactly as it was.
"""

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
# Beyond these magnitudes a model's state is treated as broken, like MuJoCo's own checks.
HUGE_POSITION = 1e8
HUGE_VELOCITY = 1e5
HUGE_ACCELERATION = 1e10
_STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_BAD_STATE_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                       mujoco.mjtWarning.mjWARN_BADQACC)
_IDENTITY_QUATERNION = (1.0, 0.0, 0.0, 0.0)


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
        raise WorldError(f'{what} contains NaN or infinity')
    return array


def _unit_quaternion(values, what='orientation'):
    quaternion = _vector(values, 4, what)
    norm = np.linalg.norm(quaternion)
    if norm < 1e-12:
        raise WorldError(f'{what} quaternion is zero')
    return quaternion / norm


def _finite_number(value, what):
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise WorldError(f'{what} is not a number: {value!r}') from None
    if not math.isfinite(number):
        raise WorldError(f'{what} is NaN or infinite: {number}')
    return number


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


def _check_model_name(name):
    if not isinstance(name, str) or not name:
        raise WorldError('model name must not be empty')
    if len(name) > MAX_MODEL_NAME_LENGTH:
        raise WorldError(f"model name '{name}' is longer than {MAX_MODEL_NAME_LENGTH} "
                         'characters')
    if SCOPE_SEPARATOR in name:
        raise WorldError(f"model name '{name}' must not contain '{SCOPE_SEPARATOR}'")
    if '/' in name:
        raise WorldError(f"model name '{name}' must not contain '/'")
    if any(character.isspace() for character in name):
        raise WorldError(f"model name '{name}' must not contain whitespace")
    if not name.isprintable() or any(character in '"\'<>&\\' for character in name):
        raise WorldError(f"model name '{name}' contains a character that is not allowed")
    if name in WORLD_FRAMES:
        raise WorldError(f"model name '{name}' is reserved for the world frame")


def _normalise_namespace(namespace):
    namespace = (namespace or '').strip()
    tokens = [token for token in namespace.split('/') if token]
    for token in tokens:
        if not (token[0].isalpha() or token[0] == '_') or not all(
                character.isalnum() or character == '_' for character in token):
            raise WorldError(f"robot namespace '{namespace}' is not a valid ROS namespace")
    return '/' + '/'.join(tokens) if tokens else ''


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
        self._next_event = math.inf
        self._kinematics_fresh = False
        self._spec = self._make_spec(gravity)
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)
        self._resize_buffers()
        mujoco.mj_forward(self._model, self._data)

    def _make_spec(self, gravity):
        spec = mujoco.MjSpec()
        spec.modelname = 'service_tutorial'
        spec.compiler.degree = False
        spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
        option = spec.option
        option.timestep = self._timestep
        option.gravity = gravity
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
        spec.worldbody.add_geom(
            name='ground_plane', type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 0.05],
            material='ground_grid', friction=[1.0, 0.005, 0.0001],
            solref=[urdf_loader.CONTACT_TIME_CONSTANT, 1.0])
        spec.worldbody.add_light(
            name='sun', type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0.0, 0.0, 10.0],
            dir=[0.3, 0.2, -1.0], diffuse=[0.7, 0.7, 0.7], specular=[0.2, 0.2, 0.2],
            castshadow=True)
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
            raise WorldError(f'no model named {name!r}')
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
            raise WorldError(f"a model named '{name}' already exists")
        namespace = _normalise_namespace(namespace)
        position = _vector(position, 3, 'position')
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

        frame = self._spec.worldbody.add_frame(pos=world_position, quat=world_orientation)
        root = None
        try:
            root = frame.attach_body(description.spec.worldbody.first_body(),
                                     name + SCOPE_SEPARATOR, '')
            model, data = self._spec.recompile(self._model, self._data)
        except Exception as error:
            self._remove_from_spec(name, frame, root)
            reason = '; '.join(line.strip() for line in str(error).splitlines() if line.strip())
            reason = reason[len('Error: '):] if reason.startswith('Error: ') else reason
            raise WorldError(f"model '{name}' does not compile: {reason}") from None
        self._model, self._data = model, data
        record = _SpawnedModel(name, namespace, description, frame, root)
        self._models[name] = record
        self._after_recompile()
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
        record = self._record(name)
        self._remove_from_spec(name, record.frame, record.root)
        self._model, self._data = self._spec.recompile(self._model, self._data)
        del self._models[name]
        self._after_recompile()
        _logger.info("deleted model '%s'", name)

    def _remove_from_spec(self, name, frame, root):
        if root is not None:
            self._spec.delete(root)
        self._spec.delete(frame)
        prefix = name + SCOPE_SEPARATOR
        for mesh in [mesh for mesh in self._spec.meshes if mesh.name.startswith(prefix)]:
            self._spec.delete(mesh)

    def _after_recompile(self):
        self._kinematics_fresh = False
        self._resize_buffers()
        for record in self._models.values():
            self._index_model(record)
        mujoco.mj_forward(self._model, self._data)
        self._schedule_events()

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
        model, data = self._model, self._data
        remaining = count
        while remaining > 0:
            chunk = remaining
            if self._next_event < math.inf:
                steps_to_event = math.ceil((self._next_event - data.time) / self._timestep - 1e-6)
                chunk = min(chunk, max(1, steps_to_event))
            mujoco.mj_getState(model, data, self._chunk_start_state, _STATE)
            mujoco.mj_step(model, data, chunk)
            remaining -= chunk
            if not self._state_is_sane():
                self._recover(chunk)
            if data.time >= self._next_event - 0.5 * self._timestep:
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
        """Replay the failed chunk from its start, resetting only the robots that blow up."""
        model, data = self._model, self._data
        mujoco.mj_setState(model, data, self._chunk_start_state, _STATE)
        self._clear_bad_state_warnings()
        # A state already broken at the start of the chunk was put there from outside.
        self._reset_models(self._broken_models(check_acceleration=False),
                           'was given NaN, infinity or a huge value')
        for _ in range(chunk):
            mujoco.mj_getState(model, data, self._step_start_state, _STATE)
            mujoco.mj_step(model, data)
            if self._state_is_sane():
                continue
            broken = self._broken_models()
            # NaN spreads to every robot through the shared constraint solver within a step,
            # but the smooth (unconstrained) acceleration stays within the robot it came from.
            culprits = [record for record in broken
                        if not _bounded(data.qacc_smooth[record.dof_index], HUGE_ACCELERATION)]
            culprits = culprits or broken or list(self._models.values())
            mujoco.mj_setState(model, data, self._step_start_state, _STATE)
            self._clear_bad_state_warnings()
            self._reset_models(culprits, 'became unstable')
            mujoco.mj_step(model, data)
            if not self._state_is_sane():
                self._reset_broken_state()
        self._clear_bad_state_warnings()

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
        mujoco.mj_forward(model, data)
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
            if record.free_qpos_adr is None:
                self._place_anchored(record, record.spawn_position, record.spawn_orientation)
        mujoco.mj_forward(model, data)
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
        raise WorldError(f"unknown reference frame '{reference_frame}'")

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
        position = _vector(position, 3, 'position')
        orientation = _unit_quaternion(orientation)
        linear_velocity = _vector(linear_velocity, 3, 'linear_velocity')
        angular_velocity = _vector(angular_velocity, 3, 'angular_velocity')
        if (np.abs(linear_velocity).max() >= HUGE_VELOCITY
                or np.abs(angular_velocity).max() >= HUGE_VELOCITY):
            raise WorldError(f'velocity of model {name!r} must stay below {HUGE_VELOCITY:g}')
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
        """Command a diff-drive robot's body twist; it lapses after cmd_vel_timeout seconds."""
        record = self._drive_record(name)
        linear_x = _finite_number(linear_x, 'linear_x')
        angular_z = _finite_number(angular_z, 'angular_z')
        drive = record.drive
        self._update_encoder_odometry(record)
        config = drive.config
        left, right = wheel_speeds(linear_x, angular_z, config.wheel_separation,
                                   config.wheel_radius)
        self._set_wheel_targets(record, left, right)
        drive.expiry = (self._data.time + self._cmd_vel_timeout if self._cmd_vel_timeout > 0.0
                        else math.inf)
        self._schedule_events()

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
