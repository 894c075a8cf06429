"""
The <gazebo> extension blocks of a URDF: per-link settings, plugin and sensor blocks.

A plugin block is kept as written (its parameters, its <ros> settings): the plugin module
parses what the simulation needs, and a ROS face reads its topic settings from the same block.
A sensor's plugin (<gazebo reference="link"><sensor><plugin>) also carries its SensorBlock:
the link, the sensor's pose and update rate, and the texts of its <ray>, <camera> or <imu>.
A <sensor> with no <plugin> is gz-sim's (Gazebo Harmonic's): its world's systems simulate it
and publish on its gz topic, so it becomes a block of its own, of the kind its type names
(plugins.sensor_kind). SDF's reader takes its <plugin>s and <sensor>s through the same
functions.
"""

from dataclasses import dataclass
import math
import types

import mujoco
import numpy as np
from service_tutorial.sim import plugins
from service_tutorial.sim.description import check_update_rate
from service_tutorial.sim.description import parse_numbers
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.validation import quoted

# The flat colours of Gazebo's own materials (gazebo-classic media/materials/scripts/
# gazebo.material), as the diffuse RGBA each gives a visual. Gazebo/SkyBlue's diffuse colour
# is plain blue; its sky blue is the ambient one, used here. Textured materials (Wood,
# Bricks...) have no flat colour and are not in the table.
GAZEBO_COLOURS = {
    'Gazebo/Grey': (0.7, 0.7, 0.7, 1.0),
    'Gazebo/DarkGrey': (0.175, 0.175, 0.175, 1.0),
    'Gazebo/White': (1.0, 1.0, 1.0, 1.0),
    'Gazebo/FlatBlack': (0.1, 0.1, 0.1, 1.0),
    'Gazebo/Black': (0.0, 0.0, 0.0, 1.0),
    'Gazebo/Red': (1.0, 0.0, 0.0, 1.0),
    'Gazebo/RedBright': (0.87, 0.26, 0.07, 1.0),
    'Gazebo/Green': (0.0, 1.0, 0.0, 1.0),
    'Gazebo/Blue': (0.0, 0.0, 1.0, 1.0),
    'Gazebo/SkyBlue': (0.13, 0.44, 0.70, 1.0),
    'Gazebo/Yellow': (1.0, 1.0, 0.0, 1.0),
    'Gazebo/ZincYellow': (0.9725, 0.9529, 0.2078, 1.0),
    'Gazebo/Purple': (1.0, 0.0, 1.0, 1.0),
    'Gazebo/Turquoise': (0.0, 1.0, 1.0, 1.0),
    'Gazebo/Orange': (1.0, 0.5088, 0.0468, 1.0),
    'Gazebo/Gold': (0.8, 0.64869, 0.120759, 1.0),
    'Gazebo/Pioneer2Body': (0.681193, 0.000923, 0.000923, 1.0),
    'Gazebo/WhiteGlow': (1.0, 1.0, 1.0, 1.0),
    'Gazebo/RedGlow': (1.0, 0.0, 0.0, 1.0),
    'Gazebo/GreenGlow': (0.0, 1.0, 0.0, 1.0),
    'Gazebo/BlueGlow': (0.0, 0.0, 1.0, 1.0),
    'Gazebo/YellowGlow': (1.0, 1.0, 0.0, 1.0),
    'Gazebo/PurpleGlow': (1.0, 0.0, 1.0, 1.0),
    'Gazebo/TurquoiseGlow': (0.0, 1.0, 1.0, 1.0),
    'Gazebo/GreyTransparent': (0.5, 0.5, 0.5, 0.5),
    'Gazebo/RedTransparent': (1.0, 0.0, 0.0, 0.5),
    'Gazebo/GreenTransparent': (0.0, 1.0, 0.0, 0.5),
    'Gazebo/BlueTransparent': (0.0, 0.0, 1.0, 0.5),
    'Gazebo/YellowTransparent': (1.0, 1.0, 0.0, 0.5),
    'Gazebo/OrangeTransparent': (1.0, 0.44, 0.0, 0.4),
}
# Names written in robot files that Gazebo itself does not define, taken as the one meant.
GAZEBO_COLOUR_ALIASES = {'Gazebo/Gray': 'Gazebo/Grey', 'Gazebo/DarkGray': 'Gazebo/DarkGrey',
                         'Gazebo/GrayTransparent': 'Gazebo/GreyTransparent'}


def gazebo_colour(material):
    """Return the RGBA of a Gazebo material name such as Gazebo/Red, or None if unknown."""
    return GAZEBO_COLOURS.get(GAZEBO_COLOUR_ALIASES.get(material, material))


@dataclass(frozen=True)
class PluginBlock:
    """One <plugin> of a robot-wide <gazebo> block, as the URDF writes it."""

    filename: str
    name: str
    parameters: types.MappingProxyType  # child tag -> its elements' texts, in document order
    ros_namespace: str = ''  # <ros><namespace>, stripped
    ros_remappings: tuple = ()  # <ros><remapping> texts, stripped
    ros_arguments: tuple = ()   # <ros><argument> texts, stripped
    sensor: object = None  # the SensorBlock of the <sensor> the plugin sits in, if any

    def texts(self, tag):
        """Return the stripped texts of every <tag> child, in document order."""
        return tuple(text.strip() for text in self.parameters.get(tag, ()))

    def text(self, tag, default=None):
        """Return the stripped text of the last <tag> child, as gazebo_ros reads it, or default."""
        values = self.texts(tag)
        return values[-1] if values else default


def read_plugin_blocks(root):
    """Return a PluginBlock for every <plugin> of the robot-wide <gazebo> blocks."""
    blocks = []
    for gazebo in root.findall('gazebo'):
        if gazebo.get('reference') is not None:
            continue
        blocks.extend(plugin_block(plugin) for plugin in gazebo.findall('plugin'))
    return tuple(blocks)


def plugin_block(plugin, sensor=None):
    """Read one <plugin>: its parameters by tag and its <ros> settings."""
    parameters = {}
    for element in plugin:
        if isinstance(element.tag, str) and element.tag != 'ros':
            parameters.setdefault(element.tag, []).append(element.text or '')
    ros = plugin.find('ros')
    settings = {}
    if ros is not None:
        settings = {
            'ros_namespace': (ros.findtext('namespace') or '').strip(),
            'ros_remappings': _stripped_texts(ros, 'remapping'),
            'ros_arguments': _stripped_texts(ros, 'argument')}
    return PluginBlock(
        filename=plugin.get('filename') or '', name=plugin.get('name') or '',
        parameters=types.MappingProxyType(
            {tag: tuple(texts) for tag, texts in parameters.items()}),
        sensor=sensor, **settings)


@dataclass(frozen=True)
class SensorBlock:
    """A <sensor> of a <gazebo reference="link"> block: where it is and what it measures."""

    link: str  # the <gazebo reference> the sensor is on
    sensor_type: str  # ray, gpu_ray, camera, imu...
    name: str
    update_rate: float  # Hz; 0: every physics step
    position: tuple  # <pose> of the sensor in the link's frame: (x, y, z) ...
    orientation: tuple  # ... and (w, x, y, z) from its roll, pitch and yaw
    values: types.MappingProxyType  # 'ray/scan/horizontal/samples' -> stripped text

    def text(self, path, default=None):
        """Return the text of an element below <sensor>, by its path of tags, or default."""
        return self.values.get(path, default)

    def number(self, path, default, *, minimum=-math.inf, above=None, whole=False):
        """
        Return a number below <sensor>, or default when it is absent.

        Refuse anything but one finite number of at least minimum (or above `above`), and a
        fraction where a whole number is asked for, naming the sensor, the tag and the text.
        """
        return _number(self.name, self.values, path, default, minimum, above, whole)


def _number(sensor_name, values, path, default, minimum=-math.inf, above=None, whole=False):
    text = values.get(path)
    if text is None:
        return default
    where = f'sensor {quoted(sensor_name)} <{path}>'
    numbers = parse_numbers(text, where)
    demand = 'a whole number' if whole else 'a number'
    if above is not None:
        demand += f' above {above:g}'
    elif minimum > -math.inf:
        demand += f' of at least {minimum:g}'
    if len(numbers) != 1 or (whole and numbers[0] != int(numbers[0])) or \
            numbers[0] < minimum or (above is not None and numbers[0] <= above):
        raise UrdfError(f'{where} must be {demand}: {quoted(text)}')
    return int(numbers[0]) if whole else numbers[0]


def read_sensor_plugin_blocks(root):
    """
    Return the blocks of the <sensor>s of the <gazebo reference="link"> blocks, and notes.

    A sensor's <plugin>s are Gazebo Classic's, each a block with the SensorBlock; a sensor
    with none is gz-sim's, one block of its own (see sensor_plugin_blocks). The notes name the
    sensors of no kind the world simulates.
    """
    link_names = {link.get('name') for link in root.findall('link')}
    blocks, notes = [], []
    for gazebo in root.findall('gazebo'):
        link = gazebo.get('reference')
        if link is None:
            continue
        for element in gazebo.findall('sensor'):
            sensor = sensor_block(element, link)
            if link not in link_names:
                raise UrdfError(f'sensor {quoted(sensor.name)} is on link {quoted(link)}, '
                                'which is not a link of the robot')
            found = sensor_plugin_blocks(element, sensor)
            if found is None:
                notes.append(f'sensor {quoted(sensor.name)} of type '
                             f'{quoted(sensor.sensor_type)} is not simulated here; it is '
                             'ignored')
            blocks.extend(found or ())
    return tuple(blocks), notes


def sensor_plugin_blocks(element, sensor):
    """
    Return the PluginBlocks of a <sensor> read into a SensorBlock, or None if it has none.

    Its <plugin>s are Gazebo Classic's and carry the sensor (registered or not: the builder
    names those it does not simulate); a sensor with no plugin is gz-sim's, simulated by its
    world's systems as the kind of its type, if the world simulates that type.
    """
    found = element.findall('plugin')
    if found:
        return tuple(plugin_block(plugin, sensor) for plugin in found)
    kind = plugins.sensor_kind(sensor.sensor_type)
    if kind is None:
        return None
    return (PluginBlock(filename=kind, name=sensor.name, parameters=types.MappingProxyType({}),
                        sensor=sensor),)


def sensor_block(element, link, pose=None):
    """
    Read a <sensor>: its type, name, update rate, pose and the texts below it.

    pose: (position, orientation (w, x, y, z)) in the link's frame, as SDF's frames resolve
    it; None: the <pose> is six numbers, x y z roll pitch yaw, as a URDF writes it.
    """
    name = (element.get('name') or '').strip()
    values = {}
    _read_values(element, '', values)
    if pose is None:
        pose_text = values.get('pose', '0 0 0 0 0 0')
        numbers = parse_numbers(pose_text, f'sensor {quoted(name)} <pose>')
        if len(numbers) != 6:
            raise UrdfError(f'sensor {quoted(name)} <pose> must be six numbers '
                            f'(x y z roll pitch yaw): {quoted(pose_text)}')
        orientation = np.zeros(4)
        mujoco.mju_euler2Quat(orientation, np.array(numbers[3:]), 'XYZ')  # URDF's and SDF's rpy
        pose = (numbers[:3], orientation)
    return SensorBlock(
        link=link, sensor_type=(element.get('type') or '').strip(), name=name,
        update_rate=check_update_rate(_number(name, values, 'update_rate', 0.0, minimum=0.0),
                                      f'sensor {quoted(name)} <update_rate>'),
        position=tuple(float(value) for value in pose[0]),
        orientation=tuple(float(value) for value in pose[1]),
        values=types.MappingProxyType(values))


def _read_values(parent, path, values):
    """
    Add the texts below parent to values by their path of tags, in document order.

    path: parent's own path below the <sensor>, with a trailing '/' ('' for the <sensor>);
    a <plugin> and what it holds are left out.
    """
    for child in parent:
        tag = child.tag
        if not isinstance(tag, str) or tag == 'plugin':
            continue
        # SDF writes some settings either way: <noise type="gaussian"> or <noise><type>.
        for attribute, text in child.attrib.items():
            values.setdefault(f'{path}{tag}/{attribute}', text.strip())
        if len(child):
            _read_values(child, f'{path}{tag}/', values)
        else:
            values[path + tag] = (child.text or '').strip()


def plugin_filenames(root):
    """Return the filename of every <plugin> in any <gazebo> block, sensors' included."""
    return tuple((plugin.get('filename') or '').strip()
                 for gazebo in root.findall('gazebo') for plugin in gazebo.iter('plugin'))


def _stripped_texts(element, tag):
    return tuple((child.text or '').strip() for child in element.findall(tag))


@dataclass(frozen=True)
class LinkSettings:
    """What the <gazebo reference="link"> blocks of one link set, None where they are silent."""

    mu: tuple = None  # (mu1, mu2): Coulomb friction along the two contact directions
    kp: float = None  # contact stiffness, N/m
    kd: float = None  # contact damping, N s/m
    material: str = None  # a Gazebo material name such as Gazebo/Red
    self_collide: bool = False  # collides with the robot's other links
    gravity: bool = True  # feels gravity


# Tag -> (LinkSettings field, kind of value). turnGravityOff is the old spelling of gravity.
_LINK_TAGS = {'mu1': 'friction', 'mu2': 'friction', 'kp': 'stiffness', 'kd': 'friction',
              'material': 'text', 'selfCollide': 'flag', 'gravity': 'flag',
              'turnGravityOff': 'flag'}


def read_link_settings(root):
    """Return {link name: LinkSettings} from the <gazebo reference="link"> blocks."""
    link_names = {link.get('name') for link in root.findall('link')}
    values = {}
    for block in root.findall('gazebo'):
        reference = block.get('reference')
        if reference is None or reference not in link_names:
            continue
        found = values.setdefault(reference, {})
        for tag, kind in _LINK_TAGS.items():
            element = block.find(tag)
            if element is None:
                continue
            text = element.get('value') if element.get('value') is not None else element.text
            what = f'gazebo <{tag}> of link {quoted(reference)}'
            found[tag] = _link_value(text or '', kind, what)
    settings = {}
    for link, found in values.items():
        if not found:
            continue
        mu = None
        if 'mu1' in found or 'mu2' in found:
            mu1 = found.get('mu1', found.get('mu2'))
            mu = (mu1, found.get('mu2', mu1))
        gravity = found.get('gravity', True)
        if found.get('turnGravityOff'):
            gravity = False
        settings[link] = LinkSettings(
            mu=mu, kp=found.get('kp'), kd=found.get('kd'), material=found.get('material'),
            self_collide=found.get('selfCollide', False), gravity=gravity)
    return settings


def _link_value(text, kind, what):
    """Return the value of one per-link tag, refusing what Gazebo could not use."""
    if kind == 'text':
        return text.strip()
    if kind == 'flag':
        value = text.strip().lower()
        if value not in ('true', 'false', '1', '0'):
            raise UrdfError(f'{what} must be true or false: {quoted(text)}')
        return value in ('true', '1')
    value = parse_numbers(text, what)
    if kind == 'stiffness':
        if len(value) != 1 or value[0] <= 0.0:
            raise UrdfError(f'{what} must be one number > 0: {quoted(text)}')
    elif len(value) != 1 or value[0] < 0.0:
        raise UrdfError(f'{what} must be one number >= 0: {quoted(text)}')
    return value[0]
