"""
ros_gz_image's image_bridge, for this world: camera topics as arguments.

    ros2 run service_tutorial image_bridge /camera/image_raw /rgbd_camera/depth_image

Each gz image topic is served as the ROS sensor_msgs/Image of the same name, from gz to ROS,
and with it the camera's CameraInfo where gz-sensors publishes it (camera_info beside the
image topic), for as long as this runs: a parameter_bridge (parameter_bridge.py) of these
mappings, under image_bridge's node name.
"""

import posixpath
import sys

from service_tutorial.node_main import program_arguments, spin_node
from service_tutorial.ros_gz.parameter_bridge import ParameterBridge
from service_tutorial.world_node.bridge_config import BridgeConfigError, GZ_TO_ROS, make_entry

USAGE = 'usage: image_bridge <gz image topic> [<gz image topic> ...]'


def image_mappings(topics):
    """Return mappings_of(node) for ParameterBridge: each topic's Image and CameraInfo."""
    def mappings_of(node):
        entries, errors = [], []
        for topic in topics:
            info = posixpath.join(posixpath.dirname(topic.rstrip('/')), 'camera_info')
            try:
                entries += [
                    make_entry(topic, topic, 'sensor_msgs/msg/Image', 'gz.msgs.Image', GZ_TO_ROS),
                    make_entry(info, info, 'sensor_msgs/msg/CameraInfo', 'gz.msgs.CameraInfo',
                               GZ_TO_ROS)]
            except BridgeConfigError as error:
                errors.append(f'image topic {topic!r}: {error}')
        return entries, errors
    return mappings_of


def main(args=None):
    """Run the image bridge until Ctrl-C; without a topic, print the usage (status 255)."""
    topics = program_arguments(args)
    if not topics:
        print(USAGE, file=sys.stderr)
        return 255
    return spin_node(lambda: ParameterBridge(image_mappings(topics), node_name='image_bridge'),
                     args=args)


if __name__ == '__main__':
    sys.exit(main())
