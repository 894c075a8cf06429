"""
gz-sim's JointPositionController and JointController as ROS sees them: a Float64 command.

The command's gz topic (/model/<model>/joint/<joint>/<index>/cmd_pos, .../cmd_vel, or the
block's) is served as the node's bridge says, std_msgs/Float64 by default; each command is
taken at the node's tick and held by the controller until the next.
"""

from service_tutorial.sim.plugins.gz_joint_controller import JointCommand
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.faces.gz_face import GzFace
from service_tutorial.world_node.gz_bridge import ROS_TO_GZ


class GzJointCommandFace(GzFace):
    """A joint controller's command, as the bridge serves it."""

    takes_commands = True

    @classmethod
    def applies_to(cls, plugin):
        """Tell whether a plugin is one of gz-sim's joint controllers."""
        return isinstance(plugin, JointCommand)

    def gz_topics(self):
        """Return the controller's gz topic with its gz type."""
        name = self.plugin.gz_topics(self.model_name)['command']
        return {'command': (name, 'gz.msgs.Double', ROS_TO_GZ)}

    def make_topics(self):
        """Take the commands at each tick."""
        self.subscription('command', self.command_callback)

    def command_callback(self, msg):
        """Hand a position or speed to the controller."""
        try:
            self.plugin.command(msg.data)
        except WorldError as error:
            self.warn_command('a joint command', error)
