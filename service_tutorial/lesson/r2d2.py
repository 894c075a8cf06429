"""
R2-D2 in the lesson: its name, its model file, and where the lesson puts it.

As the ROS 1 lesson's spawn_model_client did, R2-D2 goes 1 m above (-2, 1) in the world frame,
turned -90 degrees about z, and falls beside tinybot. The lesson's spawn_model_client, its panel
on the world's web page and the demo with its pictures all put it here. (The yard's world file
names the same pose r2d2_spawn: that is the world's data, read by the world.)
"""

import math

from service_tutorial.conversions import make_pose

R2D2_NAME = 'r2d2'
R2D2_FILE = 'r2d2.urdf'  # in the package's models/ folder
SPAWN_POSITION = (-2.0, 1.0, 1.0)  # m, in the world frame
SPAWN_YAW = -math.pi / 2  # rad: turned -90 degrees about z


def spawn_pose():
    """Return where the lesson puts R2-D2, as a geometry_msgs/Pose in the world frame."""
    return make_pose(*SPAWN_POSITION, yaw=SPAWN_YAW)
