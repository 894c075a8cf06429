"""
Keep a ROS graph to itself, for tests, benchmarks, stress runs and the pytest fixture.

DDS discovery reaches every ROS 2 process on the machine that uses the same domain, so two test
runs at once would see each other's nodes. claim_ros_domain() reserves a ROS_DOMAIN_ID that no
other user of this module on the machine holds (a lock file per domain, released by
DomainClaim.release() or when the process ends); isolate_ros_graph() claims one for the whole
process and its children, through the environment, and keeps discovery on this machine.
localhost_discovery() keeps it there for an rclpy Context initialised inside it.
"""

import contextlib
import fcntl
import os
import tempfile

# The domain ids handed out: 1 to 101, which DDS maps to distinct ports on every platform.
FIRST_DOMAIN = 1
DOMAIN_COUNT = 101
# Locks of isolate_ros_graph(), held open for as long as this process lives.
_held_claims = []


class DomainClaim:
    """A ROS domain id this process holds until release(), through a lock file."""

    def __init__(self, domain_id, lock):
        self.domain_id = domain_id
        self._lock = lock

    def release(self):
        """Let another run have the domain again."""
        if not self._lock.closed:
            self._lock.close()  # closing the file releases its lock


def claim_ros_domain():
    """Reserve a ROS domain id that nobody else on this machine holds; return a DomainClaim."""
    first = os.getpid() % DOMAIN_COUNT
    for offset in range(DOMAIN_COUNT):
        domain_id = FIRST_DOMAIN + (first + offset) % DOMAIN_COUNT
        path = os.path.join(tempfile.gettempdir(), f'service_tutorial-ros-domain-{domain_id}.lock')
        lock = open(path, 'w')
        try:
            # A lock of its own per open file: a second claim in this process skips the first.
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        return DomainClaim(domain_id, lock)
    raise RuntimeError(f'every ROS domain id {FIRST_DOMAIN}..{FIRST_DOMAIN + DOMAIN_COUNT - 1} '
                       'is held by another run on this machine')


def isolate_ros_graph():
    """Claim a free ROS domain for this process and its children; return the domain id."""
    claim = claim_ros_domain()
    _held_claims.append(claim)
    # Set before rclpy reads the environment; child processes inherit it.
    os.environ['ROS_DOMAIN_ID'] = str(claim.domain_id)
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_LOCALHOST_ONLY', None)
    return claim.domain_id


@contextlib.contextmanager
def localhost_discovery():
    """Keep discovery on this machine for a Context initialised inside; restore the rest."""
    names = ('ROS_AUTOMATIC_DISCOVERY_RANGE', 'ROS_LOCALHOST_ONLY')
    saved = {name: os.environ.get(name) for name in names}
    # rcl reads these when a Context is initialised, and never again.
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_LOCALHOST_ONLY', None)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
