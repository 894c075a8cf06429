"""
The standard's stepping: StepSimulation and the SimulateSteps action, N steps of a paused world.

The steps are taken by the node's step timer, a share of every tick (requested_steps.py), so
the world answers its other services while they run; the service answers, and the action ends,
once the last step is taken, and the world is still paused. Where the standard leaves a choice:
- Stepping needs a world that does not play: PAUSED, or STOPPED, which it leaves PAUSED. Called
  while PLAYING or QUITTING, it fails (RESULT_OPERATION_FAILED, "not paused").
- 0 steps are refused (RESULT_OPERATION_FAILED, naming the count), as is a count above
  MAX_SERVICE_STEPS for the service, which would keep its caller waiting for ever: the action
  takes any count, reports its progress ten times a second and can be cancelled.
- One stepping at a time: a request while another runs is refused (RESULT_INCORRECT_STATE).
- Playing, stopping or quitting the simulation ends a stepping early (RESULT_OPERATION_FAILED,
  saying after how many steps); a reset, a spawn or a delete happens between two chunks of
  steps, and the stepping goes on. A cancelled action answers RESULT_OPERATION_FAILED with the
  count of steps taken, and its last feedback says the same.
"""

import math

from rclpy.action import ActionServer, CancelResponse
from rclpy.callback_groups import ReentrantCallbackGroup
from service_tutorial.world_node.answers import Refusal, standard_answer
from service_tutorial.world_node.standard.simulation import state_name
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
from simulation_interfaces.srv import StepSimulation

# The most steps one StepSimulation call takes: 2000 s of simulated time at the default step,
# some tens of seconds of wall time for a few robots.
MAX_SERVICE_STEPS = 1_000_000
STEPPABLE = (SimulationState.STATE_PAUSED, SimulationState.STATE_STOPPED)


def ended(why):
    """Raise the Refusal of a stepping that ended early (why), or nothing if it did not."""
    if why is not None:
        raise Refusal(Result.RESULT_OPERATION_FAILED, why)


class SteppingServices:
    """StepSimulation and SimulateSteps for the world of a node, under its namespace."""

    FEATURES = (SimulatorFeatures.STEP_SIMULATION_SINGLE,
                SimulatorFeatures.STEP_SIMULATION_MULTIPLE,
                SimulatorFeatures.STEP_SIMULATION_ACTION)
    SPAWN_FORMATS = ()

    def __init__(self, node, simulation):
        """Step node's world (a MujocoWorld) in the state simulation (SimulationServices) says."""
        self.node = node
        self.simulation = simulation
        # These callbacks wait for the step timer, which runs in the node's default group (one
        # at a time): waiting in that group too, they would keep the timer from ever running.
        self.stepping_group = ReentrantCallbackGroup()
        self.step_srv = node.serve(
            StepSimulation, 'step_simulation', self.step_simulation_callback,
            callback_group=self.stepping_group)
        self.simulate_steps_server = ActionServer(
            node, SimulateSteps, 'simulate_steps', self.simulate_steps_callback,
            cancel_callback=self.cancel_callback, callback_group=self.stepping_group)

    def destroy(self):
        """Destroy the action server along with the node (the service goes with the node)."""
        if self.simulate_steps_server is not None:
            self.simulate_steps_server.destroy()
            self.simulate_steps_server = None

    def start(self, count, limit, **options):
        """Start count steps (StepRequest's options); return the request or raise a Refusal."""
        if count < 1:
            raise Refusal(Result.RESULT_OPERATION_FAILED, f'steps must be at least 1: {count}')
        if count > limit:
            raise Refusal(Result.RESULT_OPERATION_FAILED,
                          f'steps {count} are more than one call takes ({limit}); the '
                          'simulate_steps action takes any number and can be cancelled')
        state = self.simulation.state()
        if state not in STEPPABLE:
            raise Refusal(Result.RESULT_OPERATION_FAILED,
                          f'the simulation is not paused but {state_name(state)}; '
                          'pause it first')
        request = self.node.requested_steps.start(count, **options)
        if request is None:
            running = self.node.requested_steps.current
            raise Refusal(Result.RESULT_INCORRECT_STATE,
                          f'already stepping: {running.remaining} of {running.count} steps '
                          'to go')
        self.simulation.stopped = False
        return request

    async def step_simulation_callback(self, request, response):
        """Take request.steps steps of a paused world; answer when they are taken."""
        stepping = standard_answer(self.node, 'StepSimulation', response.result,
                                   lambda: self.start(request.steps, MAX_SERVICE_STEPS))
        if stepping is not None:
            why = await stepping.future
            standard_answer(self.node, 'StepSimulation', response.result, lambda: ended(why))
        return response

    def cancel_callback(self, goal_handle):
        """Let every stepping be cancelled: it stops at the end of the tick."""
        return CancelResponse.ACCEPT

    async def simulate_steps_callback(self, goal_handle):
        """Take the goal's steps of a paused world, telling how far they got."""
        result = SimulateSteps.Result()

        def progress(taken, remaining):
            goal_handle.publish_feedback(SimulateSteps.Feedback(
                completed_steps=taken, remaining_steps=remaining))
        stepping = standard_answer(
            self.node, 'SimulateSteps', result.result,
            lambda: self.start(goal_handle.request.steps, math.inf, progress=progress,
                               cancelled=lambda: goal_handle.is_cancel_requested))
        if stepping is None:
            goal_handle.abort()
            return result
        why = await stepping.future
        standard_answer(self.node, 'SimulateSteps', result.result, lambda: ended(why))
        if why is None:
            goal_handle.succeed()
        elif goal_handle.is_cancel_requested:
            goal_handle.canceled()
        else:
            goal_handle.abort()
        return result
