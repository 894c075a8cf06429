"""
gz-sim's JointStatePublisher system (gz-sim-joint-state-publisher-system), simulation side.

Gazebo Classic's joint state publisher (joint_state_publisher.py) with gz's names: the joints
its <joint_name>s list (each a moving joint of the model), or every moving joint; its topic is
<topic>, else /world/<world>/model/<model>/joint_state, where gz publishes a Model message that
ros_gz_bridge turns into a JointState. Each joint's state has its position, velocity and the
force its actuators apply. gz-sim 8 publishes at every step (from 8.14, at <update_rate>); here
the world node's joint_state_publish_rate paces it, as it paces Classic's.
"""

from dataclasses import dataclass

from service_tutorial.sim.plugins import gz_names
from service_tutorial.sim.plugins.gz_parameters import GzParameters
from service_tutorial.sim.plugins.joint_state_publisher import JointStateConfig
from service_tutorial.sim.plugins.joint_state_publisher import JointStatePublisher


@dataclass(frozen=True)
class GzJointStateConfig(JointStateConfig):
    """The joints published, and the gz topic the block gives (None: gz's default)."""

    robot_name: str = ''
    topic: str = None
    notes: tuple = ()


class GzJointStatePublisher(JointStatePublisher):
    """Picks the named joints' states, forces too, out of its model's."""

    title = 'JointStatePublisher system'
    is_gz_system = True

    @classmethod
    def configure(cls, block, robot):
        """Return the GzJointStateConfig of a block: its <joint_name>s, or every moving joint."""
        parameters = GzParameters(block, 'JointStatePublisher')
        named = parameters.joints('joint_name', robot, required=False)
        moving = tuple(joint.name for joint in robot.joints if joint.type != 'fixed')
        return GzJointStateConfig(joint_names=named or moving, robot_name=robot.name,
                                  topic=parameters.topic('topic'),
                                  notes=tuple(parameters.notes))

    def gz_topics(self, model_name, world_name):
        """Return the publisher's gz topic for a model of that name in a world of that name."""
        return {'joint_state': gz_names.first_valid_topic(
            self.config.topic, gz_names.world_model_topic(world_name, model_name,
                                                          'joint_state'))}

    def joint_efforts(self):
        """Return the force (N) or torque (N m) the actuators apply to each joint published."""
        dofs = self.model.joint_dof_adr[self._selected]
        return self.world.data.qfrc_actuator[dofs].copy()


PLUGIN = GzJointStatePublisher
