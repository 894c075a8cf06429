"""The camera's cost: the pace mujoco_world keeps while streaming camera images to us."""

import time

from harness import NodeProcess, sim_time_sample, wait_for_count, wait_for_world
from harness import wait_until_world_gone
from report import Table


def camera_table(observer, config):
    """Measure the pace the world keeps while its camera streams to a subscriber."""
    from sensor_msgs.msg import Image
    parameters = {'camera_enabled': True, 'camera_rate': 5.0, 'camera_width': 160,
                  'camera_height': 120}
    with NodeProcess('mujoco_world', node_name='mujoco', parameters=parameters) as process:
        wait_for_world(observer, process, 'tinybot')
        frames, subscription = observer.counter(Image, '/mujoco/camera/image_raw')
        try:
            wait_for_count(frames, process, 'camera image')
            first = frames[0]
            sim_start, wall_start, _ = sim_time_sample(observer, 'tinybot')
            time.sleep(config.camera_window)
            sim_end, wall_end, _ = sim_time_sample(observer, 'tinybot')
            count = frames[0] - first
        finally:
            observer.node.destroy_subscription(subscription)
    wait_until_world_gone(observer)
    simulated = max(sim_end - sim_start, 1e-9)
    factor = simulated / (wall_end - wall_start)
    table = Table('camera', 'Camera streaming 160x120 at 5 Hz to a subscriber, '
                  'real_time_factor 1', [
                      ('achieved factor', '.3f'), ('frames per simulated s', '.2f'),
                      ('limit factor', '.1f'), ('within', '')])
    table.rows.append([factor, count / simulated, 0.3, factor > 0.3])
    table.note = ('the mujoco_world executable; frames are rendered on the stepping thread, '
                  'so a slow (software) renderer holds the simulation back')
    return table
