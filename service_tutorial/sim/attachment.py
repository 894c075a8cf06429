"""
Models attached to the world's live spec and detached from it, every other model's state kept.

The world attaches a spawned model at the end of its spec and recompiles the spec in place;
a deleted model is detached and the spec recompiled again. Either way every other model's
entries in MuJoCo's state arrays stay in order, so the state before, without a leaving model's
share, is the start of each array after. When the live spec cannot be recompiled, the world
builds a new one from its scene with just the models it keeps, and their saved state is written
back where the new model put them.
"""

import contextlib
import warnings

import mujoco
from service_tutorial.sim.model import STATE_FIELDS

# An attach costs MuJoCo more the more the spec holds (a tinybot took 0.16 ms into an empty
# world, 2.6 ms into one of a hundred), so models go in groups of this many: into a small spec
# of their own first, which then goes into the world's in one attach.
GROUP_SIZE = 5
# What MuJoCo warns of each group's attach, and again (in Python) when it compiles the spec: the
# group goes without a prefix of its own, since its models' elements carry theirs; an XML file
# saved of the spec might not load, and the world never saves one.
EMPTY_PREFIX_WARNING = 'Attaching a spec with an empty prefix'
# MuJoCo 4 carries every element's whole state through a recompile, a deleted model's share
# left out; older versions carry positions, velocities and controls only, and the world
# carries the rest (warm starts, applied forces, activations) itself.
RECOMPILE_KEEPS_STATE = int(mujoco.__version__.split('.')[0]) >= 4


class CompileError(RuntimeError):
    """MuJoCo would not compile the edited spec; the message is its reason on one line."""


class Group:
    """The frame of a spec a group of models went under, and the names of those still there."""

    def __init__(self, frame, models):
        """Note the frame that models were attached under."""
        self.frame = frame
        self.members = {model.name for model in models}

    def leave(self, spec, model):
        """Note that model left the spec; delete the frame when no model is left under it."""
        self.members.discard(model.name)
        if not self.members:
            spec.delete(self.frame)


def attach_all(spec, models):
    """Attach models to a spec in order, without compiling it; GROUP_SIZE of them at a time."""
    models = list(models)
    for start in range(0, len(models), GROUP_SIZE):
        group = models[start:start + GROUP_SIZE]
        if len(group) == 1:
            group[0].attach(spec)
            continue
        holder = mujoco.MjSpec()
        holder.copy_during_attach = True
        for model in group:
            model.attach(holder)
        frame = spec.worldbody.add_frame()
        spec.attach(holder, prefix='', frame=frame)
        shared = Group(frame, group)
        for model in group:
            model.moved_into(spec, shared)


def attach(spec, mj_model, data, models):
    """Attach models to the live spec with one recompile; return the new MjModel and MjData."""
    try:
        attach_all(spec, models)
    except Exception as error:  # the world builds its spec afresh, as for a failed compile
        raise CompileError(compile_error(error)) from None
    kept = {} if RECOMPILE_KEEPS_STATE else {
        field: getattr(data, field).copy() for field in STATE_FIELDS}
    return _recompile(spec, mj_model, data, kept)


def detach(spec, mj_model, data, model):
    """Detach a model from the live spec; return the recompiled MjModel and MjData."""
    kept = {} if RECOMPILE_KEEPS_STATE else model.state_without(data)
    model.detach(spec)
    return _recompile(spec, mj_model, data, kept)


def _recompile(spec, mj_model, data, kept):
    try:
        with _quiet_about_groups():
            mj_model, data = spec.recompile(mj_model, data)
    except Exception as error:
        raise CompileError(compile_error(error)) from None
    for field, values in kept.items():
        getattr(data, field)[:len(values)] = values
    return mj_model, data


def build(spec, models):
    """Attach models to a fresh scene spec and compile it; return spec, MjModel and MjData."""
    attach_all(spec, models.values())
    with _quiet_about_groups():
        mj_model = spec.compile()
    return spec, mj_model, mujoco.MjData(mj_model)


@contextlib.contextmanager
def _quiet_about_groups():
    with warnings.catch_warnings():
        warnings.filterwarnings('ignore', message=EMPTY_PREFIX_WARNING, category=UserWarning)
        yield


def saved_state(models, data):
    """Return a copy of each model's share of the integration state, by model name."""
    return {name: model.saved_state(data) for name, model in models.items()}


def restore_state(models, data, saved):
    """Write saved shares of the integration state back, at the models' current places."""
    for name, values in saved.items():
        models[name].restore_state(data, values)


def compile_error(error):
    """Return a MuJoCo compiler error as one line, without its 'Error: ' prefix."""
    reason = '; '.join(line.strip() for line in str(error).splitlines() if line.strip())
    return reason[len('Error: '):] if reason.startswith('Error: ') else reason
