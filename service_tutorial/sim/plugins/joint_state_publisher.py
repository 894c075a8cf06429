"""
A model's joint states, as gazebo_ros_joint_state_publisher publishes them: no simulation.

The plugin says which of the model's moving joints its face publishes on `joint_states`
(world_node/faces/joint_states.py). A URDF asks for it with a <plugin> block naming joints in
<joint_name> elements (every moving joint if none); an MJCF model gets one for all its hinges
and slides (sim/mjcf.py). The node's joint_state_publish_rate paces it, as it paces a
drive's joint states; a block's <update_rate> is not read.
"""

from dataclasses import dataclass

import numpy as np
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.validation import quoted

# Its kind in plugins.KINDS.
JOINT_STATE_PUBLISHER = 'gazebo_ros_joint_state_publisher'


@dataclass(frozen=True)
class JointStateConfig:
    """The joints whose states are published, by their names in the robot file."""

    joint_names: tuple


class JointStatePublisher(Plugin):
    """Picks the states of the joints it names out of the world's joint states of its model."""

    title = 'joint state publisher'

    def __init__(self, config, block):
        """Keep the joints' names; which of the model's joints they are is found at bind()."""
        super().__init__(config, block)
        self._selected = np.zeros(0, dtype=int)

    @classmethod
    def configure(cls, block, robot):
        """Return the JointStateConfig of a block: its <joint_name>s, or every moving joint."""
        moving = [joint.name for joint in robot.joints if joint.type != 'fixed']
        named = block.texts('joint_name')
        for name in named:
            if name not in moving:
                raise UrdfError(f'{cls.title} names joint {quoted(name)}, which is not a '
                                'moving joint of the robot')
        return JointStateConfig(joint_names=tuple(dict.fromkeys(named)) or tuple(moving))

    def bind(self, world, model):
        """Find where the named joints are among the model's joint states."""
        super().bind(world, model)
        order = {name: index for index, name in enumerate(model.description.joints)}
        self._selected = np.array([order[name] for name in self.config.joint_names], dtype=int)

    def joint_state(self):
        """Return (names, positions, velocities) of the joints the plugin publishes."""
        _, positions, velocities = self.world.joint_state(self.model.name)
        return (list(self.config.joint_names), positions[self._selected],
                velocities[self._selected])


PLUGIN = JointStatePublisher
