"""
A standard spawn request (SpawnEntity) made into a SpawnOrder for the world to judge.

The resource is read by the world's one reader of robot files (sim/robot_files.py): a uri
inside the installed packages' shares, or a resource_string. Everything else is judged once,
by the world: the name (taken, invalid), the namespace (node.spawn_models), the initial pose
and its frame, the description; each refusal's reason becomes the standard's code
(answers.py). With allow_renaming, a taken or missing name becomes a new one: the name asked
for, or else the robot's own name, or 'entity', with the first free '_<n>' after it.
"""

from dataclasses import dataclass

from service_tutorial.conversions import pose_from_msg
from service_tutorial.sim import validation
from service_tutorial.sim.robot_files import read_text, read_uri
from service_tutorial.sim.spawning import SpawnOrder
from service_tutorial.world_node.answers import Refusal
from simulation_interfaces.msg import SpawnResult

GENERATED_NAME = 'entity'


@dataclass(frozen=True)
class PlannedSpawn:
    """A spawn request ready for the world: its SpawnOrder and its robot namespace."""

    order: SpawnOrder
    namespace: str


class SpawnPlanner:
    """Plans the spawn requests of one call, keeping the names they take apart."""

    def __init__(self, world, package_share):
        """Plan spawns into world; package_share finds a package's share folder."""
        self._package_share = package_share
        self._taken = set(world.models)
        # (uri, resource_string) -> RobotSource: a fleet's text is read and parsed once a call.
        self._robots = {}

    def plan(self, *, name, allow_renaming, uri, resource_string, entity_namespace,
             initial_pose):
        """Return the PlannedSpawn of one request, or raise why its resource is refused."""
        robot = self._robot(uri, resource_string)
        final_name = self._name(name or robot.robot_name, allow_renaming)
        position, orientation = pose_from_msg(initial_pose.pose)
        self._taken.add(final_name)
        return PlannedSpawn(order=SpawnOrder.of(
            final_name, robot, position=position, orientation=orientation,
            reference_frame=initial_pose.header.frame_id), namespace=entity_namespace)

    def _robot(self, uri, resource_string):
        key = (uri, '' if uri else resource_string)  # the uri wins
        if key not in self._robots:
            if uri:
                self._robots[key] = read_uri(uri, self._package_share)
            elif resource_string:
                self._robots[key] = read_text(resource_string)
            else:
                raise Refusal(SpawnResult.NO_RESOURCE,
                              'neither uri nor resource_string is given')
        return self._robots[key]

    def _name(self, name, allow_renaming):
        """Return the entity's name: as asked, or with allow_renaming a free one."""
        if not allow_renaming:
            return name  # the world refuses it if it is taken or invalid
        if not name:
            return self._free_name(GENERATED_NAME)
        return self._free_name(name) if name in self._taken else name

    def _free_name(self, base):
        """Return base with the first '_<n>' that makes a name no entity has."""
        number = 1
        while True:
            suffix = f'_{number}'
            name = base[:validation.MAX_MODEL_NAME_LENGTH - len(suffix)] + suffix
            if name not in self._taken:
                return name
            number += 1
