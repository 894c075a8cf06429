"""
Models attached to the world's live spec and detached from it, every other model's state kept.

The world attaches a spawned model at the end of its spec and recompiles the spec in place;
a deleted model is detached and the spec recompiled again. Either way every other model's
entries in MuJoCo's state arrays stay in order, so the state before, without a leaving model's
share, is the start of each array after. When the live spec cannot be recompiled, the world
builds a new one from its scene with just the models it keeps, and their saved state is written
back where the new model put them.
"""

import mujoco
from service_tutorial.sim.model import STATE_FIELDS


class CompileError(RuntimeError):
    """MuJoCo would not compile the edited spec; the message is its reason on one line."""


def attach(spec, mj_model, data, models):
    """Attach models to the live spec with one recompile; return the new MjModel and MjData."""
    try:
        for model in models:
            model.attach(spec)
    except Exception as error:  # the world builds its spec afresh, as for a failed compile
        raise CompileError(compile_error(error)) from None
    kept = {field: getattr(data, field).copy() for field in STATE_FIELDS}
    return _recompile(spec, mj_model, data, kept)


def detach(spec, mj_model, data, model):
    """Detach a model from the live spec; return the recompiled MjModel and MjData."""
    kept = model.state_without(data)
    model.detach(spec)
    return _recompile(spec, mj_model, data, kept)


def _recompile(spec, mj_model, data, kept):
    # MuJoCo 4 carries the whole state over itself; older versions carry positions,
    # velocities and controls only.
    try:
        mj_model, data = spec.recompile(mj_model, data)
    except Exception as error:
        raise CompileError(compile_error(error)) from None
    for field, values in kept.items():
        getattr(data, field)[:len(values)] = values
    return mj_model, data


def build(spec, models):
    """Attach models to a fresh scene spec and compile it; return spec, MjModel and MjData."""
    for model in models.values():
        model.attach(spec)
    mj_model = spec.compile()
    return spec, mj_model, mujoco.MjData(mj_model)


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
