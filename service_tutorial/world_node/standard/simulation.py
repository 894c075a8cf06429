"""
The standard's simulation state and resets: GetSimulationState, SetSimulationState, Reset.

The state follows the world: PLAYING while physics runs, PAUSED while it does not, STOPPED
while it does not since a stop (paused and reset as ResetSimulation's default scope resets:
time 0, every start-up model at its start pose, every model spawned since gone), QUITTING once
a client asked the world to quit. The `paused` parameter and the lesson's /mujoco/pause_physics
and /mujoco/unpause_physics are the same switch: pausing them pauses this, and the other way
round. Where the standard leaves a choice:
- STOPPED to PAUSED is allowed (the state's own comment allows it): nothing moves, and the
  state says PAUSED. Pausing through the lesson or the parameter leaves a STOPPED world
  STOPPED, since it is paused already.
- NO_WORLD is the state after UnloadWorld (or with the world parameter ''); asking for it
  unloads the world as UnloadWorld does. From it only a LoadWorld leads on: playing, pausing and
  stopping are incorrect transitions. LOADING_WORLD is never asked for: the world is in it only
  while a LoadWorld runs, and answers no other call meanwhile (an incorrect transition). A value
  that is no state is an incorrect transition too. Once QUITTING, no state can follow.
- A reset changes no state: a playing world plays on from the reset.
- Spawned entities are the models that were not there when the world started: a start-up model
  deleted and spawned again counts as spawned, as does one spawned under a start-up name.
- A scope with bits the standard does not define (8 to 128 but 255) is refused as a feature
  not served, naming the bits.
"""

from rclpy.parameter import Parameter
from service_tutorial.world_node.answers import Refusal, standard_answer
from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
from simulation_interfaces.srv import GetSimulationState, ResetSimulation, SetSimulationState

STATE_NAMES = {
    SimulationState.STATE_STOPPED: 'STOPPED', SimulationState.STATE_PLAYING: 'PLAYING',
    SimulationState.STATE_PAUSED: 'PAUSED', SimulationState.STATE_QUITTING: 'QUITTING',
    SimulationState.STATE_NO_WORLD: 'NO_WORLD',
    SimulationState.STATE_LOADING_WORLD: 'LOADING_WORLD'}
# The reset scopes the standard defines, as bits of ResetSimulation's scope.
SCOPE_TIME = ResetSimulation.Request.SCOPE_TIME
SCOPE_STATE = ResetSimulation.Request.SCOPE_STATE
SCOPE_SPAWNED = ResetSimulation.Request.SCOPE_SPAWNED
SCOPE_BITS = SCOPE_TIME | SCOPE_STATE | SCOPE_SPAWNED
SCOPE_MEANING = '1 time, 2 state, 4 spawned, or any sum of them; 0 and 255 all'


def state_name(state):
    """Return a state's name as the standard spells it, or its number if it is none."""
    return STATE_NAMES.get(state, str(state))


class SimulationServices:
    """The world's state and resets, as the standard has them, under the node's namespace."""

    FEATURES = (SimulatorFeatures.SIMULATION_RESET, SimulatorFeatures.SIMULATION_RESET_TIME,
                SimulatorFeatures.SIMULATION_RESET_STATE,
                SimulatorFeatures.SIMULATION_RESET_SPAWNED,
                SimulatorFeatures.SIMULATION_STATE_GETTING,
                SimulatorFeatures.SIMULATION_STATE_SETTING,
                SimulatorFeatures.SIMULATION_STATE_PAUSE)
    SPAWN_FORMATS = ()

    def __init__(self, node):
        """Serve the state of node's world (a MujocoWorld) beside the lesson's services."""
        self.node = node
        self.world = node.world
        self.stopped = False  # paused by a stop, and not played, paused or stepped since
        node.parameters.on_change(self.paused_changed, ['paused'])
        self.get_state_srv = node.serve(
            GetSimulationState, 'get_simulation_state', self.get_simulation_state_callback)
        self.set_state_srv = node.serve(
            SetSimulationState, 'set_simulation_state', self.set_simulation_state_callback)
        self.reset_srv = node.serve(
            ResetSimulation, 'reset_simulation', self.reset_simulation_callback)

    def state(self):
        """Return the simulation's state, a SimulationState constant."""
        if self.node.quitting.done():
            return SimulationState.STATE_QUITTING
        if self.node.world_loader.current is None:
            return SimulationState.STATE_NO_WORLD
        if not self.world.paused:
            return SimulationState.STATE_PLAYING
        return SimulationState.STATE_STOPPED if self.stopped else SimulationState.STATE_PAUSED

    def paused_changed(self, changes):
        """Forget the stop once the world plays again, whoever asked."""
        if not changes['paused']:
            self.stopped = False

    def get_simulation_state_callback(self, request, response):
        """Say whether the simulation is stopped, playing, paused or quitting."""
        response.state.state = self.state()
        response.result.result = Result.RESULT_OK
        return response

    def set_simulation_state_callback(self, request, response):
        """Play, pause, stop or quit, as far as the transition is allowed."""
        standard_answer(self.node, 'SetSimulationState', response.result,
                        lambda: self.change_state(request.state.state))
        return response

    def change_state(self, target):
        """Go from the current state to target, or raise a Refusal with the standard's code."""
        current = self.state()
        move = f'from {state_name(current)} to {state_name(target)}'
        if target == current:
            raise Refusal(SetSimulationState.Response.ALREADY_IN_TARGET_STATE,
                          f'already {state_name(current)}')
        if target not in STATE_NAMES:
            raise Refusal(SetSimulationState.Response.INCORRECT_TRANSITION,
                          f'no simulation state {target}: the states are '
                          + ', '.join(f'{number} {name}' for number, name in STATE_NAMES.items()))
        if current == SimulationState.STATE_QUITTING:
            raise Refusal(SetSimulationState.Response.INCORRECT_TRANSITION,
                          f'{move}: the simulation is quitting')
        if target == SimulationState.STATE_LOADING_WORLD:
            raise Refusal(SetSimulationState.Response.INCORRECT_TRANSITION,
                          f'{move}: the simulation loads a world when LoadWorld asks')
        if current == SimulationState.STATE_NO_WORLD and \
                target != SimulationState.STATE_QUITTING:
            raise Refusal(SetSimulationState.Response.INCORRECT_TRANSITION,
                          f'{move}: no world is loaded; load one with LoadWorld first')
        try:
            self._enter(target)
        except Exception as error:
            raise Refusal(SetSimulationState.Response.STATE_TRANSITION_ERROR,
                          f'{move} failed: {error}') from None
        self.node.get_logger().info(f'simulation state {move}')

    def _enter(self, target):
        """Make target the state, from any state other than QUITTING and target."""
        if target == SimulationState.STATE_PLAYING:
            self._set_paused(False)  # ends any stepping on request (MujocoWorld.paused_changed)
            return
        self.node.requested_steps.stop(STATE_NAMES[target].lower())
        if target == SimulationState.STATE_NO_WORLD:
            self.node.world_loader.unload()
            self.stopped = False
            self.node.after_reset()
            return
        self._set_paused(True)
        self.stopped = target == SimulationState.STATE_STOPPED
        if target == SimulationState.STATE_STOPPED:
            self.reset(SCOPE_BITS)
        elif target == SimulationState.STATE_QUITTING:
            self.node.quitting.set_result(True)  # main() ends once this answer is sent

    def _set_paused(self, paused):
        self.node.set_parameters([Parameter('paused', Parameter.Type.BOOL, paused)])

    def reset_simulation_callback(self, request, response):
        """Reset time, state, spawned entities, or any of them together."""
        standard_answer(self.node, 'ResetSimulation', response.result,
                        lambda: self.reset(request.scope))
        return response

    def reset(self, scope):
        """Reset what scope says (bits of SCOPE_BITS; 0 and 255: all); the state stays."""
        if scope in (ResetSimulation.Request.SCOPE_DEFAULT, ResetSimulation.Request.SCOPE_ALL):
            scope = SCOPE_BITS
        if scope & ~SCOPE_BITS:
            raise Refusal(Result.RESULT_FEATURE_UNSUPPORTED,
                          f'scope {scope} has bits the standard does not define '
                          f'({scope & ~SCOPE_BITS}); scopes are {SCOPE_MEANING}')
        node, world = self.node, self.world
        if scope & SCOPE_SPAWNED:
            for name, model in list(world.models.items()):
                if model not in node.world_loader.start_up_models:
                    node.delete_model(name)
        if scope & SCOPE_STATE:
            if scope & SCOPE_TIME:
                world.reset_simulation()
            else:
                world.reset_world()
        elif scope & SCOPE_TIME:
            world.reset_time()
        node.after_reset()
        node.get_logger().info(f'ResetSimulation: reset {self._reset_parts(scope)}')

    @staticmethod
    def _reset_parts(scope):
        parts = {SCOPE_TIME: 'time', SCOPE_STATE: 'state', SCOPE_SPAWNED: 'spawned entities'}
        return ', '.join(part for bit, part in parts.items() if scope & bit)
