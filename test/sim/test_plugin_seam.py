"""The plugin seam: the registry, raw <plugin> blocks, and a new kind driven by the world."""


import pytest
from repository import TINYBOT
from service_tutorial.sim import plugins
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins import Plugin
from service_tutorial.sim.plugins.diff_drive import DiffDrive
from service_tutorial.sim.plugins.drive_config import parameter
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.urdf.gazebo import read_plugin_blocks
from service_tutorial.sim.urdf.hardened_xml import parse_model_xml
from service_tutorial.sim.validation import WorldError
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file, spawn_robot


class TickPlugin(Plugin):
    """A plugin kind of this test only: ticks every period seconds of simulation time."""

    title = 'tick'

    @classmethod
    def configure(cls, block, robot):
        """Read the tick period."""
        return float(block.text('period'))

    @classmethod
    def build(cls, spec, config, timestep):
        """Put a site on the robot's root body, to be found again by bind()."""
        spec.worldbody.first_body().add_site(name='tick_site')

    def __init__(self, config, block):
        """Count what the world calls."""
        super().__init__(config, block)
        self.binds, self.resets, self.ticks = [], 0, []
        self._next = float('inf')

    def bind(self, world, model):
        """Find the site added by build()."""
        super().bind(world, model)
        self.binds.append(world.model.site(model.scoped('tick_site')).id)

    def next_event(self):
        """Return the next tick."""
        return self._next

    def update(self, now):
        """Tick at the world's time."""
        self.ticks.append(round(self.world.time, 9))
        self._next += self.config

    def reset(self):
        """Tick again one period from now."""
        self.resets += 1
        self._next = self.world.time + self.config


PLUGIN = TickPlugin


def ticking_robot(*periods):
    """Return a one-box robot with a tick plugin of each period."""
    blocks = ''.join(f'<gazebo><plugin name="t" filename="libtick.so"><period>{period}</period>'
                     '</plugin></gazebo>' for period in periods)
    return ('<robot name="ticker"><link name="box"><inertial><mass value="1"/><inertia '
            'ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial><collision>'
            f'<geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>{blocks}</robot>')


@pytest.fixture
def tick_kind(monkeypatch):
    monkeypatch.setitem(plugins.KINDS, 'tick', __name__)


def test_registry_maps_gazebo_filenames_to_plugin_classes():
    assert plugins.kind_of('libgazebo_ros_diff_drive.so') == 'gazebo_ros_diff_drive'
    assert plugins.kind_of('libgazebo_ros_p3d.so') is None
    assert plugins.kind_of('') is None
    assert plugins.plugin_class('gazebo_ros_diff_drive') is DiffDrive


def test_plugin_blocks_are_kept_as_written():
    root = parse_model_xml(
        '<robot name="r"><link name="a"/>'
        '<gazebo reference="a"><plugin filename="libignored.so"/></gazebo>'
        '<gazebo><plugin name="drive" filename="libgazebo_ros_diff_drive.so">'
        '<ros><namespace> /bot </namespace><remapping>cmd_vel:=cmd</remapping>'
        '<remapping>odom:=odometry</remapping><argument>--log-level debug</argument></ros>'
        '<left_joint> l1 </left_joint><left_joint>l2</left_joint><command_topic>go'
        '</command_topic></plugin><plugin filename="libgazebo_ros_camera.so"/></gazebo>'
        '</robot>')
    drive, camera = read_plugin_blocks(root)
    assert (drive.filename, drive.name) == ('libgazebo_ros_diff_drive.so', 'drive')
    assert drive.parameters['left_joint'] == (' l1 ', 'l2')
    assert drive.texts('left_joint') == ('l1', 'l2') and drive.text('left_joint') == 'l2'
    assert drive.text('missing', 'default') == 'default'
    assert drive.ros_namespace == '/bot'
    assert drive.ros_remappings == ('cmd_vel:=cmd', 'odom:=odometry')
    assert drive.ros_arguments == ('--log-level debug',)
    assert 'ros' not in drive.parameters
    assert parameter(drive, 'command_topic') == 'go'
    assert parameter(drive, 'odometry_topic', 'odom') == 'odom'
    assert (camera.filename, camera.name, dict(camera.parameters)) == (
        'libgazebo_ros_camera.so', '', {})
    assert (camera.ros_namespace, camera.ros_remappings, camera.ros_arguments) == ('', (), ())


def test_a_new_plugin_kind_is_driven_by_the_world_without_touching_it(tick_kind):
    world = World()
    spawn_robot(world, 'ticker', ticking_robot(0.05), position=(1.0, 0.0, 0.05))
    (tick,) = world.models['ticker'].plugins
    assert isinstance(tick, TickPlugin) and tick.config == 0.05
    assert world.model.site('ticker::tick_site').id == tick.binds[-1]
    assert tick.resets == 1
    world.step(100)
    # The world stops its steps at each event: the ticks fall on the period exactly.
    assert tick.ticks == [0.05, 0.1, 0.15, 0.2]
    spawn_file(world, 'tinybot', TINYBOT)
    # A model spawned later comes after the ticker's elements, which keep their ids.
    assert len(tick.binds) == 1
    assert world.model.site('ticker::tick_site').id == tick.binds[-1]
    world.reset_world()
    assert tick.resets == 2
    world.step(25)
    assert tick.ticks[-1] == 0.25


def test_a_plugin_is_bound_again_when_its_elements_move(tick_kind):
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    spawn_robot(world, 'ticker', ticking_robot(0.05), position=(1.0, 0.0, 0.05))
    (tick,) = world.models['ticker'].plugins
    world.step(30)
    world.delete_model('tinybot')
    assert len(tick.binds) == 2
    assert world.model.site('ticker::tick_site').id == tick.binds[-1]
    world.step(30)
    assert tick.ticks == [0.05, 0.1]


def test_a_second_plugin_of_a_single_kind_is_refused(tick_kind):
    with pytest.raises(UrdfError, match='model_xml carries more than one tick plugin'):
        load_urdf(ticking_robot(0.1, 0.2))
    world = World()
    with pytest.raises(WorldError, match='more than one tick plugin'):
        spawn_robot(world, 'ticker', ticking_robot(0.1, 0.2))
    assert world.model_names() == []


def test_unregistered_plugins_are_not_configured():
    description = load_urdf(ticking_robot(0.1))
    assert description.plugins == () and description.diff_drive is None
