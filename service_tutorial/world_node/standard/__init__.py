"""
The ROS 2 standard simulation interfaces (simulation_interfaces), served by the world node.

Each module serves one group of the standard's services under names relative to the node's
namespace (/spawn_entity, /get_simulation_state, ... with the default launch), beside the
lesson's /mujoco/ services: both views act on the same World.
"""
