"""
A standard spawn request (SpawnEntity) checked field by field and made into a SpawnOrder.

Each field that is wrong is refused with the standard's own code and a message naming the
value: the name (101 taken, 102 invalid), the format and the resource (103, 104, 106), the
namespace (105) and the initial pose (109, an unknown frame too). The world refuses what it
cannot build (106), and an MJCF's files it may not read (108) or cannot find (107). With
allow_renaming, a taken or missing name becomes a new one: the name asked for, or else the
robot's own name, or 'entity', with the first free '_<n>' after it.
"""

from dataclasses import dataclass

from service_tutorial.conversions import pose_from_msg
from service_tutorial.sim import validation
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WORLD_FRAMES
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.ros_names import normalise_namespace
from service_tutorial.world_node.standard.resources import read_resource
from service_tutorial.world_node.standard.results import Refusal
from simulation_interfaces.msg import SpawnResult

GENERATED_NAME = 'entity'


@dataclass(frozen=True)
class PlannedSpawn:
    """A spawn request ready for the world: its SpawnOrder and its normalised namespace."""

    order: SpawnOrder
    namespace: str


class SpawnPlanner:
    """Plans the spawn requests of one call, keeping the names they take apart."""

    def __init__(self, world, package_share):
        """Plan spawns into world; package_share finds a package's share folder."""
        self._world = world
        self._package_share = package_share
        self._taken = set(world.models)
        # (uri, resource_string) -> RobotText: a fleet's text is read and parsed once a call.
        self._robots = {}

    def plan(self, *, name, allow_renaming, uri, resource_string, entity_namespace,
             initial_pose):
        """Return the PlannedSpawn of one request, or raise a Refusal; its name is kept."""
        robot = self._robot(uri, resource_string)
        final_name = self._name(name, robot.robot_name, allow_renaming)
        try:
            namespace = normalise_namespace(entity_namespace)
        except WorldError as error:
            raise Refusal(SpawnResult.NAMESPACE_INVALID, str(error)) from None
        position, orientation = self._pose(initial_pose)
        self._taken.add(final_name)
        return PlannedSpawn(order=SpawnOrder(
            final_name, robot.urdf, position=position, orientation=orientation,
            reference_frame=initial_pose.header.frame_id, base_dir=robot.base_dir,
            model_format=robot.model_format),
            namespace=namespace)

    def _robot(self, uri, resource_string):
        key = (uri, '' if uri else resource_string)  # the uri wins
        if key not in self._robots:
            self._robots[key] = read_resource(uri, resource_string, self._package_share)
        return self._robots[key]

    def _name(self, name, robot_name, allow_renaming):
        """Return the entity's final name, or refuse the request."""
        name = name or robot_name
        if not name:
            if not allow_renaming:
                raise Refusal(SpawnResult.NAME_INVALID, 'the name is empty and the resource '
                              'names no robot; give a name or allow renaming')
            return self._free_name(GENERATED_NAME)
        try:
            validation.check_model_name(name)
        except WorldError as error:
            raise Refusal(SpawnResult.NAME_INVALID, str(error)) from None
        if name in self._taken:
            if not allow_renaming:
                raise Refusal(SpawnResult.NAME_NOT_UNIQUE, f'an entity named {quoted(name)} '
                              'already exists')
            return self._free_name(name)
        return name

    def _free_name(self, base):
        """Return base with the first '_<n>' that makes a name no entity has."""
        number = 1
        while True:
            suffix = f'_{number}'
            name = base[:validation.MAX_MODEL_NAME_LENGTH - len(suffix)] + suffix
            if name not in self._taken:
                return name
            number += 1

    def _pose(self, initial_pose):
        """Return the position and (w, x, y, z) orientation of a request, or refuse it."""
        frame = initial_pose.header.frame_id
        if frame not in WORLD_FRAMES and frame not in self._taken:
            model, separator, link = frame.partition(validation.SCOPE_SEPARATOR)
            if not (separator and model in self._world.models and link):
                raise Refusal(SpawnResult.INVALID_POSE, f'initial_pose names frame '
                              f'{quoted(frame)}, which is neither the world nor an entity')
        try:
            position, orientation = pose_from_msg(initial_pose.pose)
            return validation.position(position), validation.unit_quaternion(orientation)
        except WorldError as error:
            raise Refusal(SpawnResult.INVALID_POSE, f'initial_pose: {error}') from None
