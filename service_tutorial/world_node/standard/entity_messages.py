"""The world's entities as the standard's messages: EntityInfo, EntityState and Bounds."""

from geometry_msgs.msg import Vector3
from service_tutorial.conversions import fill_pose_msg, fill_time_msg, fill_twist_msg
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
    if model.plugins:  # a drive or sensors
        return EntityCategory.CATEGORY_ROBOT
    if model.anchored:
        return EntityCategory.CATEGORY_STATIC_OBJECT
    return EntityCategory.CATEGORY_OBJECT


def entity_info(model):
    """Return a model's EntityInfo: what SetEntityInfo stored, or its default category."""
    if model.entity_info is not None:
        return model.entity_info
    return EntityInfo(category=EntityCategory(category=default_category(model)))


def entity_states(world, names):
    """Return the EntityState of each named model, in the world frame."""
    states = []
    for name, (linear, angular) in zip(names, world.get_model_accelerations(names)):
        pose = world.get_model_state(name)
        state = EntityState()
        fill_time_msg(state.header.stamp, world.time)
        state.header.frame_id = 'world'
        fill_pose_msg(state.pose, pose.position, pose.orientation)
        fill_twist_msg(state.twist, pose.linear_velocity, pose.angular_velocity)
        fill_twist_msg(state.acceleration, linear, angular)
        states.append(state)
    return states


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
