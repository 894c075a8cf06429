"""The world's entities as the standard's messages: EntityInfo, EntityState and Bounds."""

from geometry_msgs.msg import Vector3
from service_tutorial.conversions import time_msg
from service_tutorial.sim import bounds
from simulation_interfaces.msg import Bounds, EntityCategory, EntityInfo, EntityState

CATEGORIES = {
    EntityCategory.CATEGORY_OBJECT: 'CATEGORY_OBJECT',
    EntityCategory.CATEGORY_ROBOT: 'CATEGORY_ROBOT',
    EntityCategory.CATEGORY_HUMAN: 'CATEGORY_HUMAN',
    EntityCategory.CATEGORY_DYNAMIC_OBJECT: 'CATEGORY_DYNAMIC_OBJECT',
    EntityCategory.CATEGORY_STATIC_OBJECT: 'CATEGORY_STATIC_OBJECT',
}


def default_category(model):
    """Return what a model is until a client says otherwise: robot, static object or object."""
    # A drive or sensors, joint states (an MJCF's hinges and slides), or actuators of its own.
    if model.plugins or model.description.actuators:
        return EntityCategory.CATEGORY_ROBOT
    if model.anchored:
        return EntityCategory.CATEGORY_STATIC_OBJECT
    return EntityCategory.CATEGORY_OBJECT


def entity_info(model):
    """Return a model's EntityInfo: what SetEntityInfo stored, or its default category."""
    if model.entity_info is not None:
        return model.entity_info
    return EntityInfo(category=EntityCategory(category=default_category(model)))


class EntityStates:
    """
    The EntityState messages of a world's models, kept from call to call and refilled.

    Building the nested messages anew (a state holds ten message objects) costs more than
    reading the states from MuJoCo; writing the numbers into messages kept costs a fraction.
    The n-th message listed is reused for the n-th model listed the next time, so a message
    returned holds its state until the next call only: the executor sends a response before
    it serves another call.
    """

    def __init__(self, world):
        """Read the states of world's models."""
        self._world = world
        self._messages = []  # (EntityState, its leaf messages), the first ones reused

    def __call__(self, names):
        """Return the EntityState of each named model, in the world frame."""
        world = self._world
        accelerations = world.get_model_accelerations(names)
        while len(self._messages) < len(names):
            self._messages.append(_state_message())
        stamp = time_msg(world.time)  # one for every state
        states = []
        for name, (linear, angular), (state, leaves) in zip(names, accelerations,
                                                            self._messages):
            pose = world.get_model_state(name)
            state.header.stamp = stamp
            position, orientation, velocity, turning, acceleration, angular_acceleration = leaves
            position.x, position.y, position.z = pose.position.tolist()
            orientation.w, orientation.x, orientation.y, orientation.z = \
                pose.orientation.tolist()
            velocity.x, velocity.y, velocity.z = pose.linear_velocity.tolist()
            turning.x, turning.y, turning.z = pose.angular_velocity.tolist()
            acceleration.x, acceleration.y, acceleration.z = linear.tolist()
            angular_acceleration.x, angular_acceleration.y, angular_acceleration.z = \
                angular.tolist()
            states.append(state)
        return states


def _state_message():
    """Return a new EntityState in the world frame and its messages that take numbers."""
    state = EntityState()
    state.header.frame_id = 'world'
    return state, (state.pose.position, state.pose.orientation, state.twist.linear,
                   state.twist.angular, state.acceleration.linear, state.acceleration.angular)


def fill_entity_bounds(message, world, model):
    """Write the box around a model's collision geometry, in its base frame, into Bounds."""
    box = bounds.box_in_base_frame(world, model)
    if box is None:
        message.type = Bounds.TYPE_EMPTY
        message.points = []
        return message
    message.type = Bounds.TYPE_BOX
    message.points = [Vector3(x=float(x), y=float(y), z=float(z)) for x, y, z in box]
    return message
