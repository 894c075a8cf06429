"""
The standard's entity services: spawn, delete, list, states, info and bounds of entities.

Entities are the world's models: a model the lesson spawns under /mujoco/ is an entity here,
and an entity spawned here is in the lesson's model list with its ROS interface, since both go
through the node's spawn_model/spawn_models and delete_model. An entity's category,
description and tags live on the core Model, so they go when it goes. A spawn or delete holds
simulation time while it runs, as the lesson's do.
"""

from service_tutorial.conversions import pose_from_msg, twist_from_msg
from service_tutorial.sim import frames
from service_tutorial.sim import validation
from service_tutorial.sim.description_formats import FORMATS
from service_tutorial.sim.validation import quoted, WorldError
from service_tutorial.world_node.answers import raise_refusal, Refusal, SPAWN_CODES
from service_tutorial.world_node.answers import standard_answer
from service_tutorial.world_node.packages import package_share
from service_tutorial.world_node.standard.entity_filters import EntityFilter
from service_tutorial.world_node.standard.entity_messages import CATEGORIES, entity_info
from service_tutorial.world_node.standard.entity_messages import EntityStates
from service_tutorial.world_node.standard.entity_messages import fill_entity_bounds
from service_tutorial.world_node.standard.spawn_requests import SpawnPlanner
from simulation_interfaces.msg import EntityCategory, EntityInfo, Result
from simulation_interfaces.msg import SimulatorFeatures, SpawnResult
from simulation_interfaces.srv import DeleteEntity, GetEntities, GetEntitiesStates
from simulation_interfaces.srv import GetEntityBounds, GetEntityInfo, GetEntityState
from simulation_interfaces.srv import SetEntityInfo, SetEntityState, SpawnEntities
from simulation_interfaces.srv import SpawnEntity

# Limits on what a request may ask for in one call.
MAX_SPAWN_REQUESTS = 1000
MAX_DESCRIPTION_LENGTH = 10000
MAX_TAGS = 1000
MAX_TAG_LENGTH = 256
# How many failed spawns of a batch the overall message names.
NAMED_FAILURES = 5


class EntityServices:
    """The standard's entity services of the world node (node.MujocoWorld)."""

    FEATURES = (
        SimulatorFeatures.SPAWNING, SimulatorFeatures.DELETING, SimulatorFeatures.ENTITY_TAGS,
        SimulatorFeatures.ENTITY_BOUNDS, SimulatorFeatures.ENTITY_BOUNDS_BOX,
        SimulatorFeatures.ENTITY_BOUNDS_CONVEX, SimulatorFeatures.ENTITY_CATEGORIES,
        SimulatorFeatures.SPAWNING_RESOURCE_STRING, SimulatorFeatures.ENTITY_STATE_GETTING,
        SimulatorFeatures.ENTITY_STATE_SETTING, SimulatorFeatures.ENTITY_INFO_GETTING,
        SimulatorFeatures.ENTITY_INFO_SETTING, SimulatorFeatures.SPAWNING_ENTITIES)
    SPAWN_FORMATS = tuple(FORMATS)  # 'urdf', 'mjcf', 'sdf'

    def __init__(self, node, package_share=package_share):
        """Serve node's world under names relative to node's namespace (/spawn_entity...)."""
        self.node = node
        self.world = node.world
        self.package_share = package_share
        # Each answer's messages are kept for its next call.
        self.states = EntityStates(self.world)
        self.state = EntityStates(self.world)
        self.spawn_entity_srv = node.serve(
            SpawnEntity, 'spawn_entity', self.spawn_entity_callback)
        self.spawn_entities_srv = node.serve(
            SpawnEntities, 'spawn_entities', self.spawn_entities_callback)
        self.delete_entity_srv = node.serve(
            DeleteEntity, 'delete_entity', self.delete_entity_callback)
        self.get_entities_srv = node.serve(
            GetEntities, 'get_entities', self.get_entities_callback)
        self.get_entities_states_srv = node.serve(
            GetEntitiesStates, 'get_entities_states', self.get_entities_states_callback)
        self.get_entity_state_srv = node.serve(
            GetEntityState, 'get_entity_state', self.get_entity_state_callback)
        self.set_entity_state_srv = node.serve(
            SetEntityState, 'set_entity_state', self.set_entity_state_callback)
        self.get_entity_info_srv = node.serve(
            GetEntityInfo, 'get_entity_info', self.get_entity_info_callback)
        self.set_entity_info_srv = node.serve(
            SetEntityInfo, 'set_entity_info', self.set_entity_info_callback)
        self.get_entity_bounds_srv = node.serve(
            GetEntityBounds, 'get_entity_bounds', self.get_entity_bounds_callback)

    # --- spawning and deleting ----------------------------------------------------------------

    def spawn_entity_callback(self, request, response):
        """Spawn one entity; the answer carries its final name."""
        def spawn():
            planned = SpawnPlanner(self.world, self.package_share).plan(
                name=request.name, allow_renaming=request.allow_renaming, uri=request.uri,
                resource_string=request.resource_string,
                entity_namespace=request.entity_namespace, initial_pose=request.initial_pose)
            outcome, = self.node.spawn_models([planned.order], [planned.namespace])
            left_out = raise_refusal(outcome)
            response.entity_name = planned.order.name
            return left_out
        left_out = standard_answer(self.node, 'SpawnEntity', response.result,
                                   self.node.holding_time(spawn), SPAWN_CODES)
        if left_out:
            response.result.error_message = left_out
        return response

    def spawn_entities_callback(self, request, response):
        """Spawn a batch with one recompile: one SpawnResult per request, in order."""
        def spawn_all():
            requests = request.spawn_requests
            if len(requests) > MAX_SPAWN_REQUESTS:
                raise Refusal(Result.RESULT_OPERATION_FAILED, f'{len(requests)} spawn '
                              f'requests are more than {MAX_SPAWN_REQUESTS} in one call')
            planner = SpawnPlanner(self.world, self.package_share)
            response.results = [SpawnResult() for _ in requests]

            def planned(spawn):
                return planner.plan(
                    name=spawn.name, allow_renaming=spawn.allow_renaming,
                    uri=spawn.entity_resource.uri,
                    resource_string=spawn.entity_resource.resource_string,
                    entity_namespace=spawn.entity_namespace, initial_pose=spawn.initial_pose)
            plans = [standard_answer(self.node, 'SpawnEntities', result.result,
                                     lambda spawn=spawn: planned(spawn), SPAWN_CODES)
                     for spawn, result in zip(requests, response.results)]
            ready = [(index, plan) for index, plan in enumerate(plans) if plan is not None]
            outcomes = self.node.spawn_models([plan.order for _, plan in ready],
                                              [plan.namespace for _, plan in ready])
            for (index, plan), outcome in zip(ready, outcomes):
                result = response.results[index]
                left_out = standard_answer(self.node, 'SpawnEntities', result.result,
                                           lambda outcome=outcome: raise_refusal(outcome),
                                           SPAWN_CODES)
                if result.result.result == Result.RESULT_OK:
                    result.entity_name = plan.order.name
                    result.result.error_message = left_out or ''
            _check_batch(response.results)
        standard_answer(self.node, 'SpawnEntities', response.result,
                        self.node.holding_time(spawn_all))
        return response

    def delete_entity_callback(self, request, response):
        """Delete an entity and its ROS interface."""
        def delete():
            self._model(request.entity)
            self.node.delete_model(request.entity)
        standard_answer(self.node, 'DeleteEntity', response.result, self.node.holding_time(delete))
        return response

    # --- lists and states ---------------------------------------------------------------------

    def get_entities_callback(self, request, response):
        """List the entities that pass every filter, in spawn order."""
        def listed():
            response.entities = self._filtered(request.filters)
        standard_answer(self.node, 'GetEntities', response.result, listed)
        return response

    def get_entities_states_callback(self, request, response):
        """List the entities that pass every filter with their states in the world frame."""
        def listed():
            names = self._filtered(request.filters)
            response.states = self.states(names)
            response.entities = names
        standard_answer(self.node, 'GetEntitiesStates', response.result, listed)
        return response

    def get_entity_state_callback(self, request, response):
        """Report an entity's pose, twist and acceleration in the world frame."""
        def read():
            self._model(request.entity)
            response.state, = self.state([request.entity])
        standard_answer(self.node, 'GetEntityState', response.result, read)
        return response

    def set_entity_state_callback(self, request, response):
        """Set an entity's pose and twist at once, in the world or relative to another entity."""
        standard_answer(self.node, 'SetEntityState', response.result,
                        lambda: self._set_state(request.entity, request.state))
        return response

    def _set_state(self, name, state):
        model = self._model(name)
        frame = state.header.frame_id
        try:
            frames.frame_body(frame, self.world.models, self.world.model)
        except WorldError:
            raise Refusal(SetEntityState.Response.INVALID_POSE, f'state names frame '
                          f'{quoted(frame)}, which is neither the world nor an entity') from None
        position, orientation = pose_from_msg(state.pose)
        try:
            validation.position(position)
            validation.unit_quaternion(orientation)
        except WorldError as error:
            raise Refusal(SetEntityState.Response.INVALID_POSE, str(error)) from None
        linear, angular = twist_from_msg(state.twist)
        static = entity_info(model).category.category == EntityCategory.CATEGORY_STATIC_OBJECT
        if static and any(value != 0.0 for value in linear + angular):
            raise Refusal(Result.RESULT_OPERATION_FAILED, f'entity {quoted(name)} is a static '
                          'object; it cannot be given a twist')
        self.world.set_model_state(name, position=position, orientation=orientation,
                                   linear_velocity=linear, angular_velocity=angular,
                                   reference_frame=frame)

    # --- info and bounds ----------------------------------------------------------------------

    def get_entity_info_callback(self, request, response):
        """Report an entity's category, description and tags."""
        def read():
            response.info = entity_info(self._model(request.entity))
        standard_answer(self.node, 'GetEntityInfo', response.result, read)
        return response

    def set_entity_info_callback(self, request, response):
        """Replace an entity's category, description and tags."""
        def write():
            model = self._model(request.entity)
            model.entity_info = _checked_info(request.info)
        standard_answer(self.node, 'SetEntityInfo', response.result, write)
        return response

    def get_entity_bounds_callback(self, request, response):
        """Report the box around an entity's collision geometry, in its base link's frame."""
        def read():
            fill_entity_bounds(response.bounds, self.world, self._model(request.entity))
        standard_answer(self.node, 'GetEntityBounds', response.result, read)
        return response

    # --- shared -------------------------------------------------------------------------------

    def _model(self, name):
        """Return the world's Model of an entity, or refuse with RESULT_NOT_FOUND."""
        model = self.world.models.get(name)
        if model is None:
            raise Refusal(Result.RESULT_NOT_FOUND, f'no entity named {quoted(name)}')
        return model

    def _filtered(self, filters):
        """Return the names of the entities that pass every filter, in spawn order."""
        entity_filter = EntityFilter(filters, self.world)
        return [name for name, model in self.world.models.items()
                if entity_filter.matches(model)]


def _check_batch(results):
    """Refuse a batch with ENTITIES_SPAWN_FAILED if any of its spawns failed, naming them."""
    failed = [(index, result.result.error_message) for index, result in enumerate(results)
              if result.result.result != Result.RESULT_OK]
    if failed:
        named = '; '.join(f'#{index}: {message}' for index, message
                          in failed[:NAMED_FAILURES])
        more = f'; and {len(failed) - NAMED_FAILURES} more' if len(failed) > NAMED_FAILURES \
            else ''
        raise Refusal(SpawnEntities.Response.ENTITIES_SPAWN_FAILED,
                      f'{len(failed)} of {len(results)} spawn requests failed (the others '
                      f'spawned): {named}{more}')


def _checked_info(info):
    """Return a copy of an EntityInfo to keep, or refuse it naming the value."""
    category = info.category.category
    if category not in CATEGORIES:
        raise Refusal(Result.RESULT_OPERATION_FAILED, f'category {category} is none of '
                      f'{", ".join(f"{name} ({value})" for value, name in CATEGORIES.items())}')
    if len(info.description) > MAX_DESCRIPTION_LENGTH:
        raise Refusal(Result.RESULT_OPERATION_FAILED, f'description is {len(info.description)} '
                      f'characters long, more than {MAX_DESCRIPTION_LENGTH}')
    if len(info.tags) > MAX_TAGS:
        raise Refusal(Result.RESULT_OPERATION_FAILED, f'{len(info.tags)} tags are more than '
                      f'{MAX_TAGS}')
    for tag in info.tags:
        if len(tag) > MAX_TAG_LENGTH:
            raise Refusal(Result.RESULT_OPERATION_FAILED, f'tag {quoted(tag)} is longer than '
                          f'{MAX_TAG_LENGTH} characters')
    return EntityInfo(category=EntityCategory(category=category),
                      description=info.description, tags=list(info.tags))
