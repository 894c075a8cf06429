"""
Plugins attached to a model by a Gazebo <plugin> block, one module per kind, free of ROS.

A plugin module is named in KINDS below, by the Gazebo plugin it stands in for, and defines
PLUGIN, a Plugin subclass. Loading a URDF or SDF model calls PLUGIN.configure() on the block
and PLUGIN.build() on the robot's spec (configure_plugins); spawning the robot makes one
PLUGIN(config, block) per block, and the world's step calls it through the methods of Plugin.
Adding a kind touches this table and a new module, not the world. Gazebo Classic's plugins go
by the name in their <plugin filename>; gz-sim's systems by their library's name, however the
filename writes it (libgz-sim8-diff-drive-system.so, ignition-gazebo-diff-drive-system), and
gz-sim's sensors, which have no plugin, by their <sensor type> (sensor_kind). drive_config.py,
gz_names.py, gz_parameters.py and gz_sensor.py are no kinds: they read the drives' parameters,
name gz topics and frames, read gz's parameters and what gz's sensors share.
"""

from dataclasses import dataclass
import functools
import importlib
import math
import re

from service_tutorial.sim.description import UrdfError

_MODULE = 'service_tutorial.sim.plugins.'
# Gazebo plugin name (as it appears in the <plugin filename>) -> module that stands in for it.
# A name that is part of another (gazebo_ros_imu) comes after it: kind_of() takes the first match.
KINDS = {
    'gazebo_ros_diff_drive': _MODULE + 'diff_drive',
    'gazebo_ros_skid_steer_drive': _MODULE + 'skid_steer',
    'gazebo_ros_laser': _MODULE + 'ray_sensor',
    'gazebo_ros_ray_sensor': _MODULE + 'ray_sensor',
    'gazebo_ros_camera': _MODULE + 'camera_sensor',
    'gazebo_ros_imu_sensor': _MODULE + 'imu_sensor',
    'gazebo_ros_imu': _MODULE + 'imu_sensor',
    'gazebo_ros_joint_state_publisher': _MODULE + 'joint_state_publisher',
    # gz-sim's systems, by their library's name.
    'gz-sim-diff-drive-system': _MODULE + 'gz_diff_drive',
    'gz-sim-joint-state-publisher-system': _MODULE + 'gz_joint_state_publisher',
    'gz-sim-odometry-publisher-system': _MODULE + 'gz_odometry_publisher',
    'gz-sim-joint-position-controller-system': _MODULE + 'gz_joint_position_controller',
    'gz-sim-joint-controller-system': _MODULE + 'gz_joint_controller',
}
# gz-sim's sensors, by <sensor type> (sdformat's aliases beside the names): their kinds are
# GZ_SENSOR + the type, each matched whole.
GZ_SENSOR = 'gz-sensor:'
GZ_SENSORS = {
    'gpu_lidar': _MODULE + 'gz_lidar', 'lidar': _MODULE + 'gz_lidar',
    'camera': _MODULE + 'gz_camera', 'depth_camera': _MODULE + 'gz_camera',
    'depth': _MODULE + 'gz_camera', 'rgbd_camera': _MODULE + 'gz_camera',
    'rgbd': _MODULE + 'gz_camera', 'imu': _MODULE + 'gz_imu',
    'navsat': _MODULE + 'gz_navsat', 'gps': _MODULE + 'gz_navsat',
}
# libgz-sim8-diff-drive-system.so, ignition-gazebo-diff-drive-system... -> diff-drive.
_SYSTEM = re.compile(r'^(?:lib)?(?:gz-sim\d*|ignition-gazebo\d*)-(.+)-system(?:\.so)?$')


def gz_system(filename):
    """Return gz-sim's name of a system's library (gz-sim-<name>-system), or None if none."""
    match = _SYSTEM.match((filename or '').strip())
    return f'gz-sim-{match.group(1)}-system' if match else None


def sensor_kind(sensor_type):
    """Return the kind of a gz-sim sensor of a <sensor type>, or None if it is not simulated."""
    module = GZ_SENSORS.get((sensor_type or '').strip())
    return None if module is None else GZ_SENSOR + sensor_type.strip()


def kind_of(filename):
    """Return the registered plugin kind a <plugin filename> (or a sensor kind) names, or None."""
    filename = (filename or '').strip()
    if filename.startswith(GZ_SENSOR):
        return filename if filename[len(GZ_SENSOR):] in GZ_SENSORS else None
    system = gz_system(filename)
    if system is not None:
        return system if system in KINDS else None
    return next((kind for kind in KINDS if kind in filename), None)


def plugin_class(kind):
    """Return the Plugin subclass that stands in for a registered Gazebo plugin kind."""
    if kind.startswith(GZ_SENSOR):
        return _module_plugin(GZ_SENSORS[kind[len(GZ_SENSOR):]])
    return _module_plugin(KINDS[kind])


@functools.cache
def _module_plugin(module):
    """Return a plugin module's PLUGIN; asked for by every spawn, looked up once."""
    return importlib.import_module(module).PLUGIN


def configure_plugins(blocks, robot):
    """
    Configure every block of a registered kind; return their PluginSetups and their notes.

    robot: what the plugins read of the robot (its name, links and joints, as yourdfpy's
    robot has them). A robot may carry one plugin of a single kind, and one drive of any kind.
    """
    setups, notes = [], []
    for block in blocks:
        kind = kind_of(block.filename)
        if kind is None:
            continue
        plugin = plugin_class(kind)
        if plugin.single and any(setup.kind == kind for setup in setups):
            raise UrdfError(f'model_xml carries more than one {plugin.title} plugin')
        if plugin.is_drive and any(plugin_class(setup.kind).is_drive for setup in setups):
            raise UrdfError(f'model_xml carries a {plugin.title} plugin besides another drive')
        config = plugin.configure(block, robot)
        notes.extend(getattr(config, 'notes', ()))
        setups.append(PluginSetup(kind, block, config))
    return tuple(setups), notes


def next_event(models):
    """Return the earliest time at which a plugin of the models needs its update()."""
    return min((plugin.next_event() for model in models for plugin in model.plugins),
               default=math.inf)


def update_due(models, now):
    """Update every plugin of the models whose next event is due by simulation time now."""
    for model in models:
        for plugin in model.plugins:
            if plugin.next_event() <= now:
                plugin.update(now)


def set_command_timeout(models, timeout):
    """Let the commands of the models' plugins lapse timeout s after they came (0: never)."""
    for model in models:
        for plugin in model.plugins:
            plugin.set_timeout(timeout)


@dataclass(frozen=True)
class PluginSetup:
    """A configured plugin of a robot description: its kind, raw block and parsed config."""

    kind: str
    block: object   # service_tutorial.sim.urdf.gazebo.PluginBlock, as written in the URDF
    config: object  # what the plugin class's configure() made of the block


class Plugin:
    """
    A plugin of one spawned model, driven by the world's step.

    The world calls bind() when the model's elements get their ids in a compiled model (its
    spawn, the delete of a model spawned before it, a rebuild), update() once simulation time
    reaches next_event(), and reset() when the model is put back at rest (spawn, resets,
    recovery). A plugin reads the world's model and data afresh: both change at every spawn.
    """

    # Whether a robot may carry more than one plugin of this kind, and its name in refusals.
    single = True
    title = 'plugin'
    # A drive takes velocity commands: command_velocity(), odometry(); a robot has one.
    is_drive = False
    # A gz-sim system or sensor: its topics are gz topics (gz_topics()), served on ROS as the
    # world's bridge says; a Gazebo Classic plugin's are ROS topics of its own.
    is_gz_system = False

    def __init__(self, config, block):
        """Keep the configuration parsed from the plugin's block, and the block itself."""
        self.config = config
        self.block = block
        self.world = None
        self.model = None

    @classmethod
    def configure(cls, block, robot):
        """Return the configuration of a raw block; robot is the yourdfpy robot it belongs to."""
        return None

    @classmethod
    def build(cls, spec, config, timestep):
        """Add what the plugin needs (actuators, sensors) to the robot's own MjSpec."""

    def bind(self, world, model):
        """Find the plugin's MuJoCo elements in the world's freshly compiled model."""
        self.world = world
        self.model = model

    def next_event(self):
        """Return the simulation time at which update() must next run (inf: never)."""
        return math.inf

    def update(self, now):
        """Handle every event due by simulation time now."""

    def set_timeout(self, timeout):
        """Let a command in force lapse timeout s after it came (0: never), if it takes any."""

    def reset(self):
        """Start again from rest, as at spawn."""
