"""
Keep a run's ROS graph to itself, for tests, benchmarks and stress runs.

DDS discovery reaches every ROS 2 process on the machine that uses the same domain, so two test
runs at once would see each other's nodes. isolate_ros_graph() reserves a ROS_DOMAIN_ID that
no other run using it holds (a lock file per domain, released when the process ends) and keeps
discovery on this machine.
"""

import fcntl
import os
import tempfile

# Lock files held open for as long as this process lives.
_held_locks = []


def isolate_ros_graph():
    """Claim a free ROS domain for this process and its children; return the domain id."""
    first = os.getpid() % 101
    for offset in range(101):
        domain_id = 1 + (first + offset) % 101
        path = os.path.join(tempfile.gettempdir(), f'service_tutorial-ros-domain-{domain_id}.lock')
        lock = open(path, 'w')
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        _held_locks.append(lock)
        # Set before rclpy reads the environment; child processes inherit it.
        os.environ['ROS_DOMAIN_ID'] = str(domain_id)
        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
        os.environ.pop('ROS_LOCALHOST_ONLY', None)
        return domain_id
    raise RuntimeError('every ROS domain id 1..101 is held by another run on this machine')
