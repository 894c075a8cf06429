"""
The world node's parameters, declared in code: type, range, read-only flag and description.

declare_world_parameters(node) declares all of them with ParameterDescriptors (what
`ros2 param describe` shows) and returns a WorldParameters: their typed values, kept current,
which refuses bad values set at run time with a reason and tells the node of accepted changes.
Numbers given as integers where a float is expected are accepted, at start-up
(`-p real_time_factor:=0`, a params file) and at run time (`ros2 param set /mujoco
real_time_factor 2`), which rclpy alone refuses for a DOUBLE parameter. A wrong type or a value
out of range at start-up raises ParameterError with a one-line message; run_or_exit() turns it
into that line on stderr and exit status 2. config/world.yaml documents the same defaults.
"""

import array
from collections.abc import Mapping
import math
import sys

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rcl_interfaces.msg import SetParametersResult
from rclpy.parameter import Parameter

Type = Parameter.Type
ARRAY_TYPES = (Type.BOOL_ARRAY, Type.INTEGER_ARRAY, Type.DOUBLE_ARRAY, Type.STRING_ARRAY)
TYPE_WORDS = {
    Type.BOOL: 'true or false', Type.INTEGER: 'an integer', Type.DOUBLE: 'a number',
    Type.STRING: 'a string', Type.BYTE_ARRAY: 'a list of bytes',
    Type.BOOL_ARRAY: 'a list of booleans', Type.INTEGER_ARRAY: 'a list of integers',
    Type.DOUBLE_ARRAY: 'a list of numbers', Type.STRING_ARRAY: 'a list of strings',
    Type.NOT_SET: 'no value',
}


class ParameterError(ValueError):
    """A parameter value the world cannot start with; the message is one line."""


def _number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _sequence(value):
    return isinstance(value, (list, tuple, array.array))


def _type_of(value):
    """Return the parameter type of a value, NOT_SET for None and None for a mixed list."""
    try:
        return Type.from_parameter_value(value)
    except TypeError:
        return None


def format_value(value):
    """Write a parameter value the way it is given on the command line."""
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, str):
        return repr(value)
    if value is None:
        return '(no value)'
    if _sequence(value):
        return '[' + ', '.join(format_value(item) for item in value) + ']'
    return repr(value)


class ParameterSpec:
    """One parameter: its default (which fixes its type), its meaning and the values allowed."""

    def __init__(self, name, default, description, *, minimum=None, maximum=None,
                 above_minimum=False, below_maximum=False, length=None, multiple_of=None,
                 non_empty_items=False, read_only=False):
        self.name = name
        self.default = default
        self.type = Type.from_parameter_value(default)
        self.description = description
        self.minimum = minimum
        self.maximum = maximum
        self.above_minimum = above_minimum  # the minimum itself is refused
        self.below_maximum = below_maximum  # the maximum itself is refused
        self.length = length
        self.multiple_of = multiple_of
        self.non_empty_items = non_empty_items
        self.read_only = read_only

    def allowed(self):
        """Describe the values this parameter accepts, e.g. 'a finite number > 0.0'."""
        bounds = []
        if self.minimum is not None:
            bounds.append(f'{">" if self.above_minimum else ">="} {self.minimum!r}')
        if self.maximum is not None:
            bounds.append(f'{"<" if self.below_maximum else "<="} {self.maximum!r}')
        if self.type == Type.INTEGER and self.minimum is not None and self.maximum is not None:
            return f'an integer from {self.minimum} to {self.maximum}'
        if self.type == Type.DOUBLE:
            return ' and '.join(['a finite number ' + bounds[0]] + bounds[1:]) if bounds \
                else 'a finite number'
        if self.type == Type.DOUBLE_ARRAY:
            if self.length is not None:
                return f'a list of {self.length} finite numbers'
            return f'a list of finite numbers, {self.multiple_of} per model'
        if self.type == Type.STRING_ARRAY and self.non_empty_items:
            return 'a list of non-empty strings'
        return TYPE_WORDS[self.type]

    def descriptor(self):
        """Build the ParameterDescriptor that `ros2 param describe` shows."""
        descriptor = ParameterDescriptor(
            name=self.name, type=self.type.value, description=self.description,
            additional_constraints=self.allowed(), read_only=self.read_only)
        if self.type == Type.DOUBLE and (self.minimum, self.maximum) != (None, None):
            # rclpy accepts the ends of a range; open ends are refused by problem().
            descriptor.floating_point_range = [FloatingPointRange(
                from_value=float(-math.inf if self.minimum is None else self.minimum),
                to_value=float(math.inf if self.maximum is None else self.maximum), step=0.0)]
        elif self.type == Type.INTEGER and (self.minimum, self.maximum) != (None, None):
            descriptor.integer_range = [IntegerRange(
                from_value=self.minimum, to_value=self.maximum, step=1)]
        return descriptor

    def coerce(self, value):
        """Return value as this parameter's type where no information is lost: 0 -> 0.0."""
        if self.type == Type.DOUBLE and _number(value):
            return float(value)
        if self.type == Type.DOUBLE_ARRAY and _sequence(value) and all(map(_number, value)):
            return [float(item) for item in value]
        if self.type in ARRAY_TYPES and _sequence(value) and len(value) == 0:
            return []
        return value

    def problem(self, value):
        """Return why value is not allowed, in one line, or None if it is."""
        value_type = _type_of(value)
        empty_list = self.type in ARRAY_TYPES and _sequence(value) and len(value) == 0
        if value_type != self.type and not empty_list:
            kind = TYPE_WORDS.get(value_type) or (
                'a list of mixed types' if _sequence(value) else type(value).__name__)
            return (f'parameter {self.name}:={format_value(value)} has the wrong type '
                    f'({kind}): expected {self.allowed()}')
        if self.type in (Type.DOUBLE, Type.INTEGER):
            numbers = [value]
        elif self.type == Type.DOUBLE_ARRAY:
            numbers = list(value)
            if (self.length is not None and len(numbers) != self.length) or (
                    self.multiple_of is not None and len(numbers) % self.multiple_of):
                return self._out_of_range(value)
        else:
            numbers = []
            if self.non_empty_items and any(item == '' for item in value):
                return self._out_of_range(value)
        for number in numbers:
            if not math.isfinite(number):
                return self._out_of_range(value)
            if self.minimum is not None and (
                    number < self.minimum or (self.above_minimum and number == self.minimum)):
                return self._out_of_range(value)
            if self.maximum is not None and (
                    number > self.maximum or (self.below_maximum and number == self.maximum)):
                return self._out_of_range(value)
        return None

    def _out_of_range(self, value):
        return (f'parameter {self.name}:={format_value(value)} is out of range: '
                f'expected {self.allowed()}')


WORLD_PARAMETERS = (
    ParameterSpec(
        'timestep', 0.002, 'Physics step, in seconds of simulation time',
        minimum=0.0, above_minimum=True, maximum=0.1, read_only=True),
    ParameterSpec(
        'real_time_factor', 1.0,
        'Simulated seconds per wall second: 1.0 is real time, 0.0 runs as fast as it can',
        minimum=0.0),
    ParameterSpec(
        'paused', False, 'Physics stopped; services and /clock keep answering'),
    ParameterSpec(
        'clock_publish_rate', 250.0,
        '/clock messages per second of simulation time (free-running, also of wall time)',
        minimum=0.0, above_minimum=True),
    ParameterSpec(
        'odom_publish_rate', 50.0,
        'odom messages per second of simulation time (free-running, also of wall time)',
        minimum=0.0, above_minimum=True),
    ParameterSpec(
        'joint_state_publish_rate', 50.0,
        'joint_states messages per second of simulation time (free-running, also of wall time)',
        minimum=0.0, above_minimum=True),
    ParameterSpec(
        'cmd_vel_timeout', 0.5,
        'A diff-drive robot whose last cmd_vel is older than this (s of simulation time) '
        'stops; 0.0: never',
        minimum=0.0),
    ParameterSpec(
        'world', 'yard',
        "The world loaded at start-up: a world's name (a worlds/<name>.world.xml, or Gazebo's "
        '<name>.world, <name>.sdf or <name>.sdf.xacro, of this or any installed package), a '
        'package:// uri or an absolute path of a world file',
        read_only=True),
    ParameterSpec(
        'models', ['tinybot.urdf'],
        "Models spawned at start-up, in place of the world's own unless models, model_names, "
        'model_namespaces and model_poses are all at their defaults: URDF or xacro files in '
        "the package's models/ folder or absolute paths",
        non_empty_items=True, read_only=True),
    ParameterSpec(
        'model_names', ['tinybot'],
        "Name of each start-up model ([], or not given along with models: each file's base "
        'name)', read_only=True),
    ParameterSpec(
        'model_namespaces', [''],
        "Namespace of each start-up model's topics ([], or not given along with models: none)",
        read_only=True),
    ParameterSpec(
        'model_poses', [0.0, 0.0, 0.0, 0.0],
        'x, y, z (m) and yaw (rad) of each start-up model ([], or not given along with '
        'models: all at the origin)',
        multiple_of=4, read_only=True),
    ParameterSpec(
        'scenery', 'yard.urdf',
        "Static obstacles loaded at start-up, in place of the world's own unless at the default: "
        "a URDF fixed to 'world' or an MJCF file, in the package's models/ folder or an "
        "absolute path ('': the bare plane)", read_only=True),
    ParameterSpec(
        'gui', False, "MuJoCo's interactive viewer (needs a display)", read_only=True),
    ParameterSpec(
        'web', False,
        "Serve a web page with the world in 3D and the lesson's buttons (web_host:web_port)",
        read_only=True),
    ParameterSpec(
        'web_port', 8080, 'Port of the web page (the next free one if taken)',
        minimum=1, maximum=65535, read_only=True),
    ParameterSpec(
        'web_host', '127.0.0.1',
        "Address the web page is served on: '127.0.0.1' for this machine only, '0.0.0.0' "
        'for every network it is on', read_only=True),
    ParameterSpec(
        'camera_enabled', False,
        'Publish ~/camera/image_raw and ~/camera/camera_info, rendered offscreen'),
    ParameterSpec(
        'camera_rate', 10.0, 'Camera frames per second of simulation time',
        minimum=0.0, above_minimum=True),
    ParameterSpec(
        'camera_width', 480, 'Camera image width, in pixels', minimum=1, maximum=4096),
    ParameterSpec(
        'camera_height', 360, 'Camera image height, in pixels', minimum=1, maximum=4096),
    ParameterSpec(
        'camera_position', [1.0, -1.8, 1.3],
        'Where the camera stands: x, y, z in m, world frame', length=3),
    ParameterSpec(
        'camera_look_at', [-0.9, 0.4, 0.55],
        'The point the camera looks at: x, y, z in m, world frame', length=3),
    ParameterSpec(
        'camera_fovy', 55.0, "Camera's vertical field of view, in degrees",
        minimum=0.0, above_minimum=True, maximum=180.0, below_maximum=True),
    ParameterSpec(
        'snapshot_directory', '',
        "Where ~/save_snapshot writes its PNG files ('': the node's working directory)"),
)


# Per-model details of the start-up models; [] stands for their defaults.
MODEL_DETAILS = ('model_names', 'model_namespaces', 'model_poses')


def default_parameters():
    """Return every world parameter's default, by name, in declaration order."""
    return {spec.name: spec.default for spec in WORLD_PARAMETERS}


def combination_problem(values):
    """Return why parameters that must agree with each other do not, in one line, or None."""
    files = values['models']
    counts = (len(values['model_names']), len(values['model_namespaces']),
              len(values['model_poses']) / 4)
    if any(count not in (0, len(files)) for count in counts):
        return (f'parameters models:={format_value(files)}, model_names:='
                f'{format_value(values["model_names"])}, model_namespaces:='
                f'{format_value(values["model_namespaces"])} and model_poses:='
                f'{format_value(values["model_poses"])} describe different numbers of models: '
                'expected one name, one namespace and 4 pose numbers per file, or [] for each')
    position, look_at = values['camera_position'], values['camera_look_at']
    offset = [b - a for a, b in zip(position, look_at)]
    distance = math.sqrt(sum(d * d for d in offset))
    if distance < 1e-9 or abs(offset[2] / distance) > 1.0 - 1e-9:
        return (f'parameters camera_position:={format_value(position)} and camera_look_at:='
                f'{format_value(look_at)} give the camera no view: expected two different '
                'points, not one straight above the other')
    return None


class WorldParameters(Mapping):
    """
    The world parameters of a node: their typed values by name, kept current.

    Sets at run time go through rclpy's checks of the descriptors (type, range, read-only),
    then through validate_callback; accepted changes reach the callbacks given to on_change().
    These run in the parameter services' callbacks, in the node's default callback group.
    """

    def __init__(self, node, specs=WORLD_PARAMETERS):
        self._node = node
        self._specs = {spec.name: spec for spec in specs}
        self._listeners = []
        self._checks = []
        values = {}
        # rclpy has no public accessor for the values given at start-up (-p, params files),
        # and declare_parameter() would refuse an integer for a DOUBLE parameter: read them
        # here, coerce and check them, and declare with the result.
        overrides = node._parameter_overrides
        for spec in specs:
            given = overrides.get(spec.name)
            if given is None and spec.name in MODEL_DETAILS and 'models' in overrides:
                value = []  # the defaults describe the default model, not the given ones
            elif given is None:
                value = spec.default
            elif given.type_ == Type.NOT_SET and spec.type in ARRAY_TYPES:
                value = []  # an empty list in a params file arrives without a type
            else:
                value = spec.coerce(given.value)
            problem = spec.problem(value)
            if problem is not None:
                raise ParameterError(problem)
            values[spec.name] = list(value) if spec.type in ARRAY_TYPES else value
        if set(self._specs) >= {'models', 'camera_position'}:
            problem = combination_problem(values)
            if problem is not None:
                raise ParameterError(problem)
        for spec in specs:
            self._declare(spec, values[spec.name])
        self._values = {name: _frozen(value) for name, value in values.items()}
        # rclpy joins the lists that all pre-set callbacks return: keep this one the only one.
        node.add_pre_set_parameters_callback(self.coerce_callback)
        node.add_on_set_parameters_callback(self.validate_callback)
        node.add_post_set_parameters_callback(self.changed_callback)

    def _declare(self, spec, value):
        if value != [] or spec.type not in ARRAY_TYPES:
            self._node.declare_parameter(spec.name, value, spec.descriptor(), ignore_override=True)
            return
        # declare_parameter() takes the type of [] for a byte array: declare the type, then
        # set the empty list, then make the parameter read-only if it is.
        descriptor = spec.descriptor()
        writable = spec.descriptor()
        writable.read_only = False
        self._node.declare_parameter(spec.name, spec.type, writable, ignore_override=True)
        self._node.set_parameters([Parameter(spec.name, spec.type, [])])
        self._node.set_descriptor(spec.name, descriptor)

    def __getitem__(self, name):
        """Return a parameter's current value: float, int, bool, str or a tuple."""
        return self._values[name]

    def __iter__(self):
        """Iterate over the parameter names in declaration order."""
        return iter(self._values)

    def __len__(self):
        """Return the number of world parameters."""
        return len(self._values)

    def on_change(self, callback, names=None):
        """Call callback({name: new value}) after a set of any of names (None: any) succeeds."""
        names = None if names is None else frozenset(names)
        unknown = set() if names is None else names - set(self._specs)
        if unknown:
            raise KeyError(f'no world parameter named {", ".join(sorted(unknown))}')
        self._listeners.append((names, callback))

    def refuse_when(self, check):
        """Refuse a set when check({name: value after it}) returns a reason (else None)."""
        self._checks.append(check)

    def unwatched(self):
        """Return the writable parameters no on_change() callback follows, in order."""
        if any(names is None for names, _ in self._listeners):
            return []
        watched = set().union(*(names for names, _ in self._listeners))
        return [name for name, spec in self._specs.items()
                if not spec.read_only and name not in watched]

    def coerce_callback(self, parameters):
        """Turn integers given for numbers into floats before rclpy checks the types."""
        coerced = []
        for parameter in parameters:
            spec = self._specs.get(parameter.name)
            if spec is not None and parameter.type_ != Type.NOT_SET:
                value = spec.coerce(parameter.value)
                if value is not parameter.value:
                    parameter = Parameter(parameter.name, spec.type, value)
            coerced.append(parameter)
        return coerced

    def validate_callback(self, parameters):
        """Refuse values that rclpy's range checks let through, with the reason."""
        pending = dict(self._values)
        for parameter in parameters:
            spec = self._specs.get(parameter.name)
            if spec is None:
                continue
            problem = spec.problem(parameter.value)
            if problem is not None:
                return SetParametersResult(successful=False, reason=problem)
            pending[parameter.name] = parameter.value
        if set(self._specs) >= {'models', 'camera_position'}:
            problem = combination_problem(pending)
            if problem is not None:
                return SetParametersResult(successful=False, reason=problem)
        for check in self._checks:
            problem = check(pending)
            if problem is not None:
                return SetParametersResult(successful=False, reason=problem)
        return SetParametersResult(successful=True)

    def changed_callback(self, parameters):
        """Keep the values current and tell the callbacks that follow the changed ones."""
        changed = {}
        for parameter in parameters:
            if parameter.name in self._specs:
                self._values[parameter.name] = changed[parameter.name] = _frozen(parameter.value)
        if not changed:
            return
        for names, callback in self._listeners:
            relevant = changed if names is None else {
                name: value for name, value in changed.items() if name in names}
            if not relevant:
                continue
            try:
                callback(relevant)
            except Exception as error:  # the value is set: a failure must not end the node
                self._node.get_logger().error(
                    f'applying {", ".join(relevant)} failed: {error!r}')


def _frozen(value):
    return tuple(value) if _sequence(value) else value


def declare_world_parameters(node):
    """Declare every world parameter on node and return their values; ParameterError if bad."""
    return WorldParameters(node)


def run_or_exit(program, main, *args, **kwargs):
    """Run a node's main(); a ParameterError ends it with `program: <the line>` and status 2."""
    # The executable's name, not sys.argv[0]: started as a module or a file (as colcon test
    # and launch may start it), the world still introduces itself as mujoco_world.
    try:
        return main(*args, **kwargs)
    except ParameterError as error:
        print(f'{program}: {error}', file=sys.stderr)
        sys.exit(2)
