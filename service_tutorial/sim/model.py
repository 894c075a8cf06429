"""One model spawned into the world: its description, its MuJoCo elements, state and plugins."""

import itertools

import mujoco
import numpy as np
from service_tutorial.sim import frames
from service_tutorial.sim import plugins
from service_tutorial.sim import validation
from service_tutorial.sim.validation import SCOPE_SEPARATOR
from service_tutorial.sim.validation import WorldError

# What a model's integration state is made of, in MjData, carried over when the spec is rebuilt.
STATE_FIELDS = ('qpos', 'qvel', 'qacc_warmstart', 'qfrc_applied', 'act', 'ctrl')
# Numbers the placements of every model (spawn, set state, reset), the latest highest.
_PLACEMENTS = itertools.count(1)


def _run(addresses, first, end, size):
    """Return the start and end of the entries of joints first to end (not included)."""
    if first == end:
        return 0, 0
    return int(addresses[first]), int(addresses[end]) if end < len(addresses) else size


def _offset(description):
    """Tell whether a description's root stands anywhere but at its own origin."""
    return (tuple(description.root_position) != (0.0, 0.0, 0.0)
            or tuple(description.root_orientation) != (1.0, 0.0, 0.0, 0.0))


class Model:
    """
    A spawned robot: its name, its URDF description, where it was spawned, and its plugins.

    Its bodies, joints and actuators carry the prefix '<name>::' in the world's MuJoCo model;
    the world calls bind() whenever their ids in the compiled model may have changed, which
    finds them again by name.
    """

    def __init__(self, name, description, position, orientation):
        """Describe a model whose URDF frame goes to a world pose; it has no elements yet."""
        self.name = name
        self.description = description
        if description.anchored or _offset(description):
            # The root link sits where the URDF's joint to the world link puts it, or the
            # top body where its MJCF places it.
            position, orientation = frames.compose(position, orientation,
                                                   description.root_position,
                                                   description.root_orientation)
        self.spawn_position = np.array(position, dtype=float)
        self.spawn_orientation = np.array(orientation, dtype=float)
        self.frame = None  # the frame of the world's spec the model's root is attached to
        self.group = None  # the attachment.Group it came in with, if it came in one
        self.plugins = tuple(plugins.plugin_class(setup.kind)(setup.config, setup.block)
                             for setup in description.plugins)
        # When the world last placed it (spawn, set state, reset), and whether the world has
        # since put it back at its spawn pose because it became unstable.
        self.placed = 0
        self.recovered = False
        # What a client said the model is (the standard interfaces' category, description and
        # tags), or None until one does; it goes with the model.
        self.entity_info = None
        # Where its elements are in the compiled model, found again by bind().
        self.root_id = 0
        self.free_qpos_adr = self.free_dof_adr = None
        self.qpos_index = self.dof_index = np.zeros(0, dtype=int)
        self.act_index = self.actuator_index = np.zeros(0, dtype=int)
        self.joint_qpos_adr = self.joint_dof_adr = np.zeros(0, dtype=int)

    def scoped(self, element_name):
        """Return the name a URDF element of this model has in the world's MuJoCo model."""
        return self.name + SCOPE_SEPARATOR + element_name

    def element_id(self, mj_model, kind, element_name):
        """Return the id of one of the model's elements (an mjtObj kind) in a compiled model."""
        # mj_name2id, not mj_model.body(name): an accessor costs several times as much on a
        # model just compiled, which a spawn's binding pays for every element it looks up.
        element = mujoco.mj_name2id(mj_model, kind, self.scoped(element_name))
        if element < 0:
            raise KeyError(f'{self.scoped(element_name)!r} is not in the compiled model')
        return element

    @property
    def anchored(self):
        """Return True if the model is fixed to the world rather than free to move."""
        return self.free_qpos_adr is None

    def checked_state(self, *, position, orientation, linear_velocity, angular_velocity):
        """Return the ModelState asked for this model, or refuse a value it cannot have."""
        state = frames.ModelState(
            position=validation.position(position),
            orientation=validation.unit_quaternion(orientation),
            linear_velocity=validation.vector(linear_velocity, 3, 'linear_velocity'),
            angular_velocity=validation.vector(angular_velocity, 3, 'angular_velocity'))
        validation.check_velocity(state.linear_velocity, 'linear_velocity', self.name)
        validation.check_velocity(state.angular_velocity, 'angular_velocity', self.name)
        if self.anchored and (np.any(state.linear_velocity) or np.any(state.angular_velocity)):
            raise WorldError(f"model '{self.name}' is anchored to the world; it cannot be "
                             'given a velocity')
        return state

    def mark_placed(self):
        """Note that the model was just put somewhere on purpose, not by a recovery."""
        self.placed = next(_PLACEMENTS)
        self.recovered = False

    def plugin(self, plugin_type):
        """Return the model's first plugin of a type, or None."""
        return next((plugin for plugin in self.plugins if isinstance(plugin, plugin_type)),
                    None)

    def drive(self):
        """Return the model's drive plugin (diff drive, skid steer), or None."""
        return next((plugin for plugin in self.plugins if plugin.is_drive), None)

    def attach(self, spec):
        """Attach the model's bodies to a world spec where it stands now, under its prefix."""
        if self.frame is None:
            position, orientation = self.spawn_position, self.spawn_orientation
        else:
            position, orientation = np.array(self.frame.pos), np.array(self.frame.quat)
        # Named by the prefix alone, which no element of the model's can be: moved_into()
        # finds it by name. Its fields are set on it: add_frame(pos=..., ...) costs MuJoCo's
        # bindings several times as much.
        self.frame = spec.worldbody.add_frame()
        self.frame.pos, self.frame.quat, self.frame.name = position, orientation, self.scoped('')
        self.group = None
        # The world's spec copies what it attaches (copy_during_attach), so the description,
        # shared by every model spawned from the same URDF, stays as it was loaded.
        self.frame.attach_body(self.description.spec.worldbody.first_body(),
                               self.name + SCOPE_SEPARATOR, '')

    def moved_into(self, spec, group):
        """Take up the model's frame in spec, where the spec it was attached to was attached."""
        self.frame = spec.frame(self.scoped(''))
        self.group = group

    def detach(self, spec):
        """
        Delete everything attach() brought to the spec.

        Deleting the frame deletes the bodies attached to it and the actuators, sensors and
        excludes that name them; the assets and the default class the attach brought along go
        by name. Each delete costs MuJoCo a pass over the whole spec, hence one for the tree.
        """
        spec.delete(self.frame)
        if self.group is not None:
            self.group.leave(spec, self)
            self.group = None
        robot = self.description.spec
        for assets, find in ((robot.meshes, spec.mesh), (robot.materials, spec.material),
                             (robot.textures, spec.texture)):
            for asset in assets:
                spec.delete(find(self.scoped(asset.name)))
        default = spec.find_default(self.scoped(robot.default.name))
        if default is not None:
            spec.delete(default)
        self.frame = None

    def bind(self, world):
        """Find the model's elements in the world's compiled model, then its plugins'."""
        mj_model = world.model
        description = self.description
        self.root_id = self.element_id(mj_model, mujoco.mjtObj.mjOBJ_BODY, description.root_link)
        # MuJoCo numbers bodies depth first, each body's joints one after the other in body
        # order, and their qpos and dof entries in joint order: a model, a subtree of the
        # world's body, has a run of each. Found with a few array sums, not a lookup by name
        # per link: a batch spawn binds every new model.
        bodies = int(np.count_nonzero(mj_model.body_rootid == self.root_id))
        joint_counts = mj_model.body_jntnum
        first = int(joint_counts[:self.root_id].sum())
        end = first + int(joint_counts[self.root_id:self.root_id + bodies].sum())
        self.qpos_index = np.arange(*_run(mj_model.jnt_qposadr, first, end, mj_model.nq))
        self.dof_index = np.arange(*_run(mj_model.jnt_dofadr, first, end, mj_model.nv))
        self.free_qpos_adr = self.free_dof_adr = None
        if end > first and mj_model.jnt_type[first] == mujoco.mjtJoint.mjJNT_FREE:
            self.free_qpos_adr, self.free_dof_adr = (int(self.qpos_index[0]),
                                                     int(self.dof_index[0]))
        joints = np.array([self.element_id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name)
                           for name in description.joints], dtype=int)
        self.joint_qpos_adr = mj_model.jnt_qposadr[joints].astype(int)
        self.joint_dof_adr = mj_model.jnt_dofadr[joints].astype(int)
        self.actuator_index = np.array(
            [self.element_id(mj_model, mujoco.mjtObj.mjOBJ_ACTUATOR, name)
             for name in description.actuators], dtype=int)
        self.act_index = np.array(
            [address for start, count in zip(mj_model.actuator_actadr[self.actuator_index],
                                             mj_model.actuator_actnum[self.actuator_index])
             if start >= 0 for address in range(start, start + count)], dtype=int)
        for plugin in self.plugins:
            plugin.bind(world, self)

    def _state_index(self, field):
        """Return the indices of the model's entries in an MjData array of STATE_FIELDS."""
        if field == 'qpos':
            return self.qpos_index
        if field == 'act':
            return self.act_index
        if field == 'ctrl':
            return self.actuator_index
        return self.dof_index

    def saved_state(self, data, fields=STATE_FIELDS):
        """Return a copy of the model's share of the integration state, by MjData field."""
        return {field: getattr(data, field)[self._state_index(field)].copy()
                for field in fields}

    def state_without(self, data):
        """Return a copy of the integration state by MjData field, without the model's share."""
        return {field: np.delete(getattr(data, field), self._state_index(field))
                for field in STATE_FIELDS}

    def restore_state(self, data, saved):
        """Write a share of the integration state saved by saved_state() back."""
        for field, value in saved.items():
            getattr(data, field)[self._state_index(field)] = value

    def put_back(self, mj_model, data):
        """Put the model's joints back at their spawn values, at rest."""
        data.qpos[self.qpos_index] = mj_model.qpos0[self.qpos_index]
        data.qvel[self.dof_index] = 0.0
        data.qacc[self.dof_index] = 0.0
        data.qacc_warmstart[self.dof_index] = 0.0

    def reset_plugins(self):
        """Let every plugin start again from rest."""
        for plugin in self.plugins:
            plugin.reset()

    def return_to_spawn(self, mj_model):
        """Mark the model placed after a reset; one without a free joint goes back in place."""
        self.mark_placed()
        if self.anchored:
            self.place_anchored(mj_model, self.spawn_position, self.spawn_orientation)

    def place_anchored(self, mj_model, position, orientation):
        """Move a model that has no free joint, in the compiled model and in the spec."""
        mj_model.body_pos[self.root_id] = position
        mj_model.body_quat[self.root_id] = orientation
        self.frame.pos = position
        self.frame.quat = orientation

    def place(self, mj_model, data, state):
        """Put the model's base at a world-frame state; an anchored model only takes the pose."""
        if self.anchored:
            self.place_anchored(mj_model, state.position, state.orientation)
            return
        qpos, dof = self.free_qpos_adr, self.free_dof_adr
        data.qpos[qpos:qpos + 3] = state.position
        data.qpos[qpos + 3:qpos + 7] = state.orientation
        data.qvel[dof:dof + 3] = state.linear_velocity
        # A free joint's angular velocity is expressed in the body frame.
        data.qvel[dof + 3:dof + 6] = frames.rotate_back(state.orientation,
                                                        state.angular_velocity)
        data.qacc_warmstart[self.dof_index] = 0.0

    def joint_state(self, data):
        """Return (URDF joint names, positions, velocities) of the model's moving joints."""
        return (list(self.description.joints), data.qpos[self.joint_qpos_adr].copy(),
                data.qvel[self.joint_dof_adr].copy())
