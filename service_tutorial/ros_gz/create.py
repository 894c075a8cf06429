"""
ros_gz_sim's create, for this world: spawn one robot with its command line, then end.

    ros2 run service_tutorial create -name burger -file model.sdf -x 1 -y 0.5 -z 0.01
    ros2 run service_tutorial create -topic robot_description -name tb4
    ros2 run service_tutorial create --ros-args -p file:=model.sdf -p name:=burger

The arguments are ros_gz_sim create's (Jazzy): flags -world, -file, -param, -string, -topic,
-name, -allow_renaming and the pose -x -y -z -R -P -Y (m, rad), written -flag value, --flag
value or -flag=value; and all of them but -param as ROS parameters, which come first, as
create takes them. The robot comes from the parameters' file, string or topic, else from the
flags' file, param (a parameter of this node holding the XML), string or topic. -topic waits for
the latched (transient local) std_msgs/String robot_state_publisher publishes. -file is read by
the world: a path is made absolute here, a uri (package://, model://, file://) is sent as it is.
It spawns through the world's SpawnEntity (simulation_interfaces), waiting for the service as
create waits for the server, and ends with status 0 once the world has the robot; 1 with the
world's reason on stderr if it refuses it, or with what is wrong if there is no robot to send
or a flag has a bad value. Flags create does not know (Gazebo Classic's -entity and
-robot_namespace, which launch files still pass) are named and ignored, as create's flag parser
lets them pass. -allow_renaming takes a true or false after it, as launch files write it.
-world names the world to spawn in: this world serves one, and refuses a spawn meant for
another name.
"""

import os
import sys

from geometry_msgs.msg import PoseStamped
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from rclpy.task import Future
from service_tutorial.conversions import fill_quaternion_msg
from service_tutorial.node_main import program_arguments, run_node
from simulation_interfaces.msg import Result
from simulation_interfaces.srv import GetCurrentWorld, SpawnEntity
from std_msgs.msg import String

# create's flags and their default values; the type of each is its default's.
FLAGS = {'world': '', 'file': '', 'param': '', 'string': '', 'topic': '', 'name': '',
         'allow_renaming': False, 'x': 0.0, 'y': 0.0, 'z': 0.0, 'R': 0.0, 'P': 0.0, 'Y': 0.0}
POSE_FLAGS = ('x', 'y', 'z', 'R', 'P', 'Y')
# As robot_state_publisher publishes robot_description: the last one, kept for late joiners.
DESCRIPTION_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
# Said after a refused -file path: the world's rule, and what a user of Gazebo's create can do.
FILE_NOTE = ('create: note: -file is read by the world, and the world reads files only in the '
             "installed packages' share folders (it serves every process on the graph, so it "
             'reads no file a request names elsewhere); install the file with its package, or '
             'give its XML with -string "$(cat FILE)" if it names no file beside it (meshes)')
# Wall time between two messages that say what create is waiting for, in s.
WAITING_PERIOD = 5.0
USAGE = ('usage: create [-world WORLD] [-file FILE | -param PARAM | -string XML | -topic TOPIC] '
         '[-name NAME] [-allow_renaming] [-x X] [-y Y] [-z Z] [-R ROLL] [-P PITCH] [-Y YAW]')


class CreateArgumentError(ValueError):
    """A command line create cannot run with."""


def parse_flags(arguments):
    """Return (flags given as {name: value}, the words create ignores) of create's arguments."""
    given, ignored = {}, []
    words = list(arguments)
    while words:
        word = words.pop(0)
        name, equals, value = word.lstrip('-').partition('=')
        if not word.startswith('-') or name not in FLAGS:
            ignored.append(word)
            continue
        default = FLAGS[name]
        if not equals and isinstance(default, bool):
            value = words.pop(0) if words and words[0].lower() in ('true', 'false') else 'true'
        elif not equals:
            if not words:
                raise CreateArgumentError(f'-{name} needs a value')
            value = words.pop(0)
        given[name] = _flag_value(name, default, value)
    return given, ignored


def _flag_value(name, default, value):
    """Return a flag's value as its default's type, or refuse it."""
    if isinstance(default, bool):
        if value.lower() not in ('true', 'false', '1', '0'):
            raise CreateArgumentError(f'-{name} takes true or false, not {value!r}')
        return value.lower() in ('true', '1')
    if isinstance(default, float):
        try:
            return float(value)
        except ValueError:
            raise CreateArgumentError(f'-{name} takes a number, not {value!r}') from None
    return value


def file_uri(file):
    """Return a -file as the uri the world reads: a path made absolute, a uri as it is."""
    return file if '://' in file else 'file://' + os.path.abspath(file)


class Create(Node):
    """ros_gz_sim's create: one spawn through the world's SpawnEntity, with create's options."""

    def __init__(self, arguments):
        """Read the flags and parameters; raise CreateArgumentError if they cannot spawn."""
        super().__init__('ros_gz_sim')
        flags, ignored = parse_flags(arguments)
        if ignored:
            shown = ' '.join(word or "''" for word in ignored)
            self.get_logger().warning(f'create ignores what it does not know: {shown}')
        parameters = {name: self.declare_parameter(name, default).value
                      for name, default in FLAGS.items() if name != 'param'}
        self.world_name = parameters['world'] or flags.get('world', '')
        self.source = self._source(parameters, flags)
        self.file_path_given = self.source[0] == 'uri' and '://' not in (
            parameters['file'] or flags.get('file', ''))
        # A parameter that is not 0 wins over its flag, as in create.
        self.pose = [parameters[name] or flags.get(name, 0.0) for name in POSE_FLAGS]
        self.entity_name = parameters['name'] or flags.get('name', '')
        self.allow_renaming = parameters['allow_renaming'] or flags.get('allow_renaming', False)
        self.spawn_entity_cli = self.create_client(SpawnEntity, 'spawn_entity')
        self.get_current_world_cli = self.create_client(GetCurrentWorld, 'get_current_world')
        self.description_sub = None
        self._description = Future()

    def _source(self, parameters, flags):
        """Return ('uri' or 'text' or 'topic', value): where the robot comes from."""
        for name, kind in (('file', 'uri'), ('string', 'text'), ('topic', 'topic')):
            if parameters[name]:
                return kind, file_uri(parameters[name]) if kind == 'uri' else parameters[name]
        if flags.get('file'):
            return 'uri', file_uri(flags['file'])
        if flags.get('param'):
            value = self.declare_parameter(flags['param'], '').value
            if not isinstance(value, str) or not value:
                raise CreateArgumentError(f'no XML in parameter {flags["param"]!r} '
                                          '(give it with --ros-args -p NAME:=XML)')
            return 'text', value
        for name, kind in (('string', 'text'), ('topic', 'topic')):
            if flags.get(name):
                return kind, flags[name]
        raise CreateArgumentError('give the robot with -file, -param, -string or -topic '
                                  f'(or the parameters file, string or topic)\n{USAGE}')

    def robot_text(self, executor):
        """Return the robot's XML of a -topic, waiting for it as long as it takes."""
        topic = self.source[1]
        self.description_sub = self.create_subscription(
            String, topic, self.description_callback, DESCRIPTION_QOS)
        while not self._description.done():
            self.get_logger().info(f'waiting for the robot on topic {topic}')
            executor.spin_until_future_complete(self._description, WAITING_PERIOD)
        return self._description.result()

    def description_callback(self, msg):
        """Keep the first robot description heard."""
        if not self._description.done():
            self._description.set_result(msg.data)

    def wait_for(self, client):
        """Wait for a world service, as long as it takes, saying so now and then."""
        while not client.wait_for_service(timeout_sec=WAITING_PERIOD):
            self.get_logger().warning(f'waiting for the service {client.srv_name}')

    def call(self, executor, client, request):
        """Call a world service once it is there; return its answer."""
        self.wait_for(client)
        future = client.call_async(request)
        executor.spin_until_future_complete(future)
        return future.result()

    def spawn(self, executor):
        """Spawn the robot; return the exit status (0 spawned, 1 refused, reason on stderr)."""
        if self.world_name:
            current = self.call(executor, self.get_current_world_cli, GetCurrentWorld.Request())
            here = current.world.name
            if current.result.result == Result.RESULT_OK and here != self.world_name:
                print(f'create: no world named {self.world_name!r}: the world here is '
                      f'{here!r}', file=sys.stderr)
                return 1
        # MuJoCo (for the orientation) is imported once the world is up: started beside it, as
        # launch files start create, the import would take the cores from the world's start-up.
        self.wait_for(self.spawn_entity_cli)
        from service_tutorial.sim.frames import rpy_quaternion
        request = SpawnEntity.Request(name=self.entity_name, allow_renaming=self.allow_renaming)
        kind, value = self.source
        if kind == 'uri':
            request.uri = value
        else:
            request.resource_string = \
                value if kind == 'text' else self.robot_text(executor)
        request.initial_pose = PoseStamped()
        position = request.initial_pose.pose.position
        position.x, position.y, position.z = self.pose[:3]
        fill_quaternion_msg(request.initial_pose.pose.orientation, rpy_quaternion(self.pose[3:]))
        response = self.call(executor, self.spawn_entity_cli, request)
        if response.result.result != Result.RESULT_OK:
            print(f'create: the world did not spawn it: {response.result.error_message}',
                  file=sys.stderr)
            if self.file_path_given:
                print(FILE_NOTE, file=sys.stderr)
            return 1
        self.get_logger().info(f'spawned {response.entity_name!r}')
        return 0


def main(args=None):
    """Spawn one robot as ros_gz_sim create does; exit 0 once spawned."""
    from rclpy.executors import SingleThreadedExecutor

    def spawn(node):
        executor = SingleThreadedExecutor(context=node.context)
        executor.add_node(node)
        return node.spawn(executor)
    return run_node(lambda: Create(program_arguments(args)), spawn, args=args,
                    program='create', errors=(CreateArgumentError,))


if __name__ == '__main__':
    sys.exit(main())
