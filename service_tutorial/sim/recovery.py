"""
Instability: finding the model that broke a physics step, and sorting the step out without it.

A model whose state becomes NaN, infinite or huge is put back at its spawn pose at rest and
the step is taken again; a model that breaks a step again after that is removed. Every other
model goes through the step as if nothing had happened.
"""

import collections
from dataclasses import dataclass

import mujoco
import numpy as np
from service_tutorial.sim.core_logs import core_logger
from service_tutorial.sim.validation import bounded
from service_tutorial.sim.validation import HUGE_ACCELERATION
from service_tutorial.sim.validation import HUGE_POSITION
from service_tutorial.sim.validation import HUGE_VELOCITY

# The world's log: one name for everything that happens to its models.
_logger = core_logger('service_tutorial.world')

STATE = mujoco.mjtState.mjSTATE_INTEGRATION
_BAD_STATE_WARNINGS = (mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
                       mujoco.mjtWarning.mjWARN_BADQACC)
# What a sound robot keeps of its state when the whole data has to be reset.
_KEPT_FIELDS = ('qpos', 'qvel', 'act', 'ctrl')
UNSTABLE_AGAIN = 'became unstable again after it was put back at its spawn pose'


@dataclass(frozen=True)
class Removal:
    """A model the world removed by itself so that the others could go on."""

    name: str
    time: float  # simulation time of the removal, s
    reason: str  # what the model did, as the world's log says: 'became unstable again...'


def take_steps(model, data, count=1, *, logger=_logger):
    """Step the physics; return False if MuJoCo gave up on a step, out of memory for one."""
    try:
        mujoco.mj_step(model, data, count)
    except mujoco.FatalError as error:
        logger.warning('MuJoCo: %s', str(error).splitlines()[0])
        return False
    return True


class Recovery:
    """Watches a world's steps: keeps where a chunk of steps began, and repairs a bad chunk."""

    def __init__(self, world, logger=_logger):
        """Watch world, telling logger what goes wrong; resize() follows every recompile."""
        self._world = world
        self._logger = logger
        self._removed = []
        self.resize()

    def resize(self):
        """Make room for a state of the world's current model."""
        size = mujoco.mj_stateSize(self._world.model, STATE)
        self._chunk_start_state = np.empty(size)
        self._step_start_state = np.empty(size)

    def take_removed(self):
        """Return the Removal of every model removed since the last call, oldest first."""
        removed, self._removed = self._removed, []
        return removed

    def start_chunk(self):
        """Remember the state a chunk of steps starts from."""
        world = self._world
        mujoco.mj_getState(world.model, world.data, self._chunk_start_state, STATE)

    def state_is_sane(self):
        """Return True if MuJoCo saw no bad state and every value is within the limits."""
        data = self._world.data
        if any(data.warning[kind].number for kind in _BAD_STATE_WARNINGS):
            return False
        return (bounded(data.qpos, HUGE_POSITION) and bounded(data.qvel, HUGE_VELOCITY)
                and bounded(data.qacc, HUGE_ACCELERATION)
                and bounded(data.act, HUGE_VELOCITY))

    def _broken_models(self, check_acceleration=True):
        """
        Return the models whose state is not finite or huge.

        The acceleration is only meaningful right after a step, not after a state is restored.
        """
        data = self._world.data
        return [model for model in self._world.models.values()
                if not (bounded(data.qpos[model.qpos_index], HUGE_POSITION)
                        and bounded(data.qvel[model.dof_index], HUGE_VELOCITY)
                        and bounded(data.act[model.act_index], HUGE_VELOCITY)
                        and (not check_acceleration
                             or bounded(data.qacc[model.dof_index], HUGE_ACCELERATION)))]

    def recover(self, chunk):
        """
        Replay the failed chunk from its start, one step at a time, sorting out each bad step.

        A robot that breaks a step is put back at its spawn pose at rest and the step is taken
        again; a robot that breaks a step again after that is removed from the world. The
        others go through the step as if nothing had happened.
        """
        world = self._world
        mujoco.mj_setState(world.model, world.data, self._chunk_start_state, STATE)
        self._clear_bad_state_warnings()
        # A state already broken at the start of the chunk was put there from outside.
        self.reset_models(self._broken_models(check_acceleration=False),
                          'was given NaN, infinity or a huge value')
        for _ in range(chunk):
            mujoco.mj_getState(world.model, world.data, self._step_start_state, STATE)
            completed = take_steps(world.model, world.data, logger=self._logger)
            # Every retake resets a robot for the first time or removes one, so this ends.
            for _ in range(2 * len(world.models) + 1):
                if completed and self.state_is_sane():
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
        data = self._world.data
        broken = self._broken_models()
        # NaN spreads through the constraint solver to every robot in touch with the one it
        # came from, but the smooth (unconstrained) acceleration stays within that robot.
        smooth = [model for model in broken
                  if not bounded(data.qacc_smooth[model.dof_index], HUGE_ACCELERATION)]
        # Failing that, the robot placed last, by a spawn or a set state, is the likeliest.
        return max(smooth or broken, key=lambda model: model.placed, default=None)

    def _crowded_model(self):
        """Return the model in most contacts in the step MuJoCo gave up on, or None."""
        mj_model, data = self._world.model, self._world.data
        roots = {model.root_id: model for model in self._world.models.values()}
        geoms = np.asarray(data.contact.geom, dtype=int).reshape(-1)
        counts = collections.Counter(
            int(body) for body in mj_model.body_rootid[mj_model.geom_bodyid[geoms]]
            if body in roots)
        most = max(counts.values(), default=0)
        candidates = ([roots[body] for body, count in counts.items() if count == most]
                      or list(self._world.models.values()))
        return max(candidates, key=lambda model: model.placed, default=None)

    def _retake_step_without(self, culprit):
        """Undo the last step, reset or remove the culprit, and take the step again."""
        world = self._world
        mujoco.mj_setState(world.model, world.data, self._step_start_state, STATE)
        self._clear_bad_state_warnings()
        if culprit.recovered:
            self._logger.error("model '%s' %s; it is removed from the world", culprit.name,
                               UNSTABLE_AGAIN)
            world.rebuild({name: model for name, model in world.models.items()
                           if model is not culprit})
            self._removed.append(Removal(culprit.name, world.time, UNSTABLE_AGAIN))
        else:
            self.reset_models([culprit], 'became unstable')
            culprit.recovered = True
        # A further retake of this step starts from here, without the culprit's bad state.
        mujoco.mj_getState(world.model, world.data, self._step_start_state, STATE)
        return take_steps(world.model, world.data, logger=self._logger)

    def _clear_bad_state_warnings(self):
        for kind in _BAD_STATE_WARNINGS:
            self._world.data.warning[kind].number = 0

    def reset_models(self, models, reason):
        """Put models back at their spawn pose at rest, saying why in the world's log."""
        world = self._world
        for model in models:
            self._logger.warning("model '%s' %s; it is put back to its spawn pose at rest",
                                 model.name, reason)
            model.put_back(world.model, world.data)
        if models:
            world.state_changed()
            for model in models:
                model.reset_plugins()
            world.schedule_events()

    def _reset_broken_state(self):
        """Reset the whole data, keeping the state of every robot that is still sound."""
        world = self._world
        mj_model, data = world.model, world.data
        self._logger.warning('the simulation state is broken; resetting it, keeping the robots '
                             'whose state is sound')
        broken = self._broken_models()
        kept = {name: model.saved_state(data, _KEPT_FIELDS)
                for name, model in world.models.items() if model not in broken}
        time = data.time
        mujoco.mj_resetData(mj_model, data)
        data.time = time
        world.state_changed()
        for name, model in world.models.items():
            if name in kept:
                model.restore_state(data, kept[name])
            elif model.plugins:
                self._logger.warning("model '%s' is put back to its spawn pose at rest", name)
                model.reset_plugins()
        world.forward()
        world.schedule_events()
