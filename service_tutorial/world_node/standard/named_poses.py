"""
The standard's named poses: GetNamedPoses and GetNamedPoseBounds, from the current world's file.

A world file names poses to spawn, park or drive to (sim/world_files.py), with a description,
tags and, where it gives them, bounds: a box (two opposite corners) or a sphere (centre, then
radius, 0, 0), in the world frame, as GetEntities' filters take them. A pose without bounds
answers TYPE_EMPTY. In the no-world state there are no named poses.
"""

from geometry_msgs.msg import Point, Pose, Quaternion, Vector3
from service_tutorial.sim.validation import quoted
from service_tutorial.world_node.answers import Refusal, standard_answer
from service_tutorial.world_node.standard.entity_filters import tags_test
from simulation_interfaces.msg import Bounds, NamedPose, Result, SimulatorFeatures
from simulation_interfaces.srv import GetNamedPoseBounds, GetNamedPoses

BOUNDS_TYPES = {'': Bounds.TYPE_EMPTY, 'box': Bounds.TYPE_BOX, 'sphere': Bounds.TYPE_SPHERE}
MAX_NAME_LENGTH = 256


class NamedPoseServices:
    """The standard's named-pose services of the world node (node.MujocoWorld)."""

    FEATURES = (SimulatorFeatures.NAMED_POSES, SimulatorFeatures.POSE_BOUNDS)

    def __init__(self, node):
        """Serve the named poses of node's current world (node.world_loader)."""
        self.node = node
        self.loader = node.world_loader
        self.get_named_poses_srv = node.serve(
            GetNamedPoses, 'get_named_poses', self.get_named_poses_callback)
        self.get_named_pose_bounds_srv = node.serve(
            GetNamedPoseBounds, 'get_named_pose_bounds', self.get_named_pose_bounds_callback)

    def get_named_poses_callback(self, request, response):
        """List the current world's named poses that pass the tags filter, in file order."""
        def listed():
            matches = tags_test(request.tags)
            response.poses = [named_pose_msg(pose) for pose in self.loader.named_poses.values()
                              if matches is None or matches(set(pose.tags))]
        standard_answer(self.node, 'GetNamedPoses', response.result, listed)
        return response

    def get_named_pose_bounds_callback(self, request, response):
        """Give the bounds of one named pose of the current world."""
        def bounds():
            name = request.name
            pose = self.loader.named_poses.get(name)
            if pose is None:
                shown = quoted(name[:MAX_NAME_LENGTH]) + ('...' if len(name) > MAX_NAME_LENGTH
                                                          else '')
                world = self.loader.current
                where = 'no world is loaded' if world is None else \
                    f'world {quoted(world.world.name)} names ' + (
                        ', '.join(quoted(known) for known in self.loader.named_poses)
                        or 'no poses')
                raise Refusal(Result.RESULT_NOT_FOUND, f'no named pose {shown}: {where}')
            response.bounds = Bounds(type=BOUNDS_TYPES[pose.bounds_type], points=[
                Vector3(x=x, y=y, z=z) for x, y, z in pose.bounds_points])
        standard_answer(self.node, 'GetNamedPoseBounds', response.result, bounds)
        return response


def named_pose_msg(pose):
    """Return the NamedPose message of a world file's NamedPose."""
    (x, y, z), (w, qx, qy, qz) = pose.position, pose.orientation
    return NamedPose(name=pose.name, description=pose.description, tags=list(pose.tags),
                     pose=Pose(position=Point(x=x, y=y, z=z),
                               orientation=Quaternion(x=qx, y=qy, z=qz, w=w)))
