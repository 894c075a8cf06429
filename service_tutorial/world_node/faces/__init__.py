"""
The ROS faces of the plugins, one module per kind, mirroring sim/plugins/.

FACES lists every kind of face, in the order a model's topics are made; each meets the
PluginFace protocol (face.py). A new plugin's face is one module here and one entry below.
"""

from service_tutorial.world_node.faces.camera import CameraFace
from service_tutorial.world_node.faces.drive import DriveFace
from service_tutorial.world_node.faces.gz_camera import GzCameraFace
from service_tutorial.world_node.faces.gz_diff_drive import GzDiffDriveFace
from service_tutorial.world_node.faces.gz_imu import GzImuFace
from service_tutorial.world_node.faces.gz_joint_command import GzJointCommandFace
from service_tutorial.world_node.faces.gz_joint_states import GzJointStatesFace
from service_tutorial.world_node.faces.gz_lidar import GzLidarFace
from service_tutorial.world_node.faces.gz_navsat import GzNavSatFace
from service_tutorial.world_node.faces.gz_odometry import GzOdometryFace
from service_tutorial.world_node.faces.imu import ImuFace
from service_tutorial.world_node.faces.joint_states import JointStatesFace
from service_tutorial.world_node.faces.laser import LaserScanFace
from service_tutorial.world_node.faces.odom_tf import OdomTfFace

FACES = (DriveFace, OdomTfFace, LaserScanFace, CameraFace, ImuFace, JointStatesFace,
         GzDiffDriveFace, GzOdometryFace, GzJointStatesFace, GzJointCommandFace, GzLidarFace,
         GzCameraFace, GzImuFace, GzNavSatFace)
