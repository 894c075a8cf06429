"""
Plugins attached to a model by a Gazebo <plugin> block, one module per kind, free of ROS.

A plugin module is named in KINDS below, by the Gazebo plugin it stands in for, and defines
PLUGIN, a Plugin subclass. Loading a URDF calls PLUGIN.configure() on the block and
PLUGIN.build() on the robot's spec; spawning the robot makes one PLUGIN(config, block) per
block, and the world's step calls it through the methods of Plugin. Adding a kind touches this
table and a new module, not the world. drive_config.py is no kind: it reads the parameters of
the drives.
"""

from dataclasses import dataclass
import importlib
import math

# Gazebo plugin name (as it appears in the <plugin filename>) -> module that stands in for it.
# A name that is part of another (gazebo_ros_imu) comes after it: kind_of() takes the first match.
KINDS = {
    'gazebo_ros_diff_drive': 'service_tutorial.sim.plugins.diff_drive',
    'gazebo_ros_skid_steer_drive': 'service_tutorial.sim.plugins.skid_steer',
    'gazebo_ros_laser': 'service_tutorial.sim.plugins.ray_sensor',
    'gazebo_ros_ray_sensor': 'service_tutorial.sim.plugins.ray_sensor',
    'gazebo_ros_camera': 'service_tutorial.sim.plugins.camera_sensor',
    'gazebo_ros_imu_sensor': 'service_tutorial.sim.plugins.imu_sensor',
    'gazebo_ros_imu': 'service_tutorial.sim.plugins.imu_sensor',
    'gazebo_ros_joint_state_publisher': 'service_tutorial.sim.plugins.joint_state_publisher',
}


def kind_of(filename):
    """Return the registered plugin kind a <plugin filename> names, or None."""
    return next((kind for kind in KINDS if kind in (filename or '')), None)


def plugin_class(kind):
    """Return the Plugin subclass that stands in for a registered Gazebo plugin kind."""
    return importlib.import_module(KINDS[kind]).PLUGIN


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
