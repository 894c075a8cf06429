"""
The Gazebo skid-steer plugin of ROS 1 (gazebo_ros_skid_steer_drive), simulation side.

Four driven wheels, the two on each side turning alike: a diff drive with two wheel pairs of
one separation and diameter, limited by <torque>, without an acceleration limit, and with
ground-truth odometry, as the ROS 1 plugin has. Turning makes the wheels skid sideways, so a
skid-steer robot turns less than its wheel speeds say, as a real one does.
"""

from service_tutorial.sim.plugins.diff_drive import DiffDrive
from service_tutorial.sim.plugins.drive_config import read_skid_steer


class SkidSteer(DiffDrive):
    """A skid-steer robot's drive at run time: a diff drive with two pairs of wheels."""

    title = 'skid-steer'

    @classmethod
    def configure(cls, block, robot):
        """Return the DiffDriveConfig of a skid-steer block (ROS 1 names)."""
        return read_skid_steer(block, robot)


PLUGIN = SkidSteer
