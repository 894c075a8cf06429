"""
The DDS participants of a world's process: the one place that decides where sensors publish.

A 2048x2048 camera frame is 12 MB on a reliable topic: hundreds of fragments. Sent through the
world node's own participant, frames in flight held up its service answers: in the sensor storm
of scripts/stress, answers the world had sent at once reached eight clients together 1.3 to 3 s
later, while /clock kept coming. Published from a context of their own (a participant with its
own sockets, shared memory and sending thread), they leave the answers' way clear: the storm's
p99 answer time went from 1.7 s to 0.15 s.

But a second participant of the same process and domain has a price: Fast DDS 2.14 can hang
deleting a participant while another participant of the same process and domain delivers
discovery data to it (seen in the test suite: rmw's set_listener(nullptr) spun for good while a
discovery callback waited for its mutex). So the rule is one participant per domain per process,
and the sensors' own is the one exception, taken only where its deletion can be put off to the
end of the process:

- A world in rclpy's default context (the executable's, a test session's, a benchmark's) lives
  as long as its process. Its sensors get a context of their own, one per world context, made
  with the first sensor topic. rmw deletes a context's participant with the context's last
  node, so both participants are held by a hidden node each (_sensors_participant, and
  _sensors_neighbour in the world's context) while world nodes and a test's nodes come and go;
  without the second, each test that ended with its world deleted the world context's
  participant beside the sensors'. When the world's context shuts down (at the latest at exit),
  the sensors' participant goes first, then the world's hidden node: one deletion beside a
  neighbour per process, not one per world.
- A world in a context of its own may end while its process goes on: the testing fixture
  (service_tutorial/testing/) makes one per world, alone on a domain of its own, and shuts it
  down after the test. Its sensors' topics go out on the world node's own participant, the
  domain's only one in the process, which then ends with its context beside no neighbour.
"""

import atexit
import threading

import rclpy
from rclpy.context import Context
from rclpy.utilities import get_default_context

_lock = threading.Lock()
_contexts = {}  # id of a world's context -> (the sensors' Context, the nodes keeping them up)


def sensors_have_own_participant(world_context):
    """Tell whether a world in world_context gets a participant of its own for its sensors."""
    return world_context is get_default_context()


def sensor_context(world_context):
    """Return the sensors' context beside a world's context, made once and kept up."""
    key = id(world_context)
    with _lock:
        if key not in _contexts:
            context = Context()
            # No command-line arguments: a node rename given to the world must not name these.
            context.init(args=[], initialize_logging=False,
                         domain_id=world_context.get_domain_id())
            # Hidden (a leading underscore): `ros2 node list --all` shows it.
            keepers = tuple(rclpy.create_node(
                name, context=kept, use_global_arguments=False,
                start_parameter_services=False, enable_rosout=False)
                for name, kept in (('_sensors_participant', context),
                                   ('_sensors_neighbour', world_context)))
            _contexts[key] = (context, keepers)
            world_context.on_shutdown(lambda: _end_sensor_context(key))
        return _contexts[key][0]


def _end_sensor_context(key):
    with _lock:
        context, keepers = _contexts.pop(key, (None, ()))
    if context is not None:
        sensors_keeper, world_keeper = keepers
        sensors_keeper.destroy_node()
        context.try_shutdown()
        world_keeper.destroy_node()  # the last participant of the domain here, if no other


@atexit.register
def _end_sensor_contexts():
    for key in list(_contexts):
        _end_sensor_context(key)
