"""
The <gazebo> extension blocks of a URDF: per-link surface settings, plugin and sensor blocks.

A plugin block is kept as written (its parameters, its <ros> settings): the plugin module
parses what the simulation needs, and a ROS face reads its topic settings from the same block.
A sensor's plugin (<gazebo reference="link"><sensor><plugin>) also carries its SensorBlock:
the link, the sensor's pose and update rate, and the texts of its <ray>, <camera> or <imu>.
"""

from dataclasses import dataclass
import math
import types

import mujoco
import numpy as np
from service_tutorial.sim.urdf.hardened_xml import parse_numbers
from service_tutorial.sim.urdf.hardened_xml import UrdfError
from service_tutorial.sim.validation import quoted


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
        blocks.extend(_plugin_block(plugin) for plugin in gazebo.findall('plugin'))
    return tuple(blocks)


def _plugin_block(plugin, sensor=None):
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
    """Return a PluginBlock, with its SensorBlock, for every <plugin> of a link's <sensor>."""
    link_names = {link.get('name') for link in root.findall('link')}
    blocks = []
    for gazebo in root.findall('gazebo'):
        link = gazebo.get('reference')
        if link is None:
            continue
        for element in gazebo.findall('sensor'):
            plugins = element.findall('plugin')
            if not plugins:
                continue  # Gazebo would run it, but nothing would publish what it measures
            sensor = _sensor_block(element, link)
            if link not in link_names:
                raise UrdfError(f'sensor {quoted(sensor.name)} is on link {quoted(link)}, '
                                'which is not a link of the robot')
            blocks.extend(_plugin_block(plugin, sensor) for plugin in plugins)
    return tuple(blocks)


def _sensor_block(element, link):
    """Read a <sensor>: its type, name, update rate, pose and the texts below it."""
    name = (element.get('name') or '').strip()
    values = {}
    for child in element.iter():
        if child is element or not isinstance(child.tag, str):
            continue
        tags = []
        ancestor = child
        while ancestor is not element:
            tags.append(ancestor.tag)
            ancestor = ancestor.getparent()
        if 'plugin' in tags:
            continue
        path = '/'.join(reversed(tags))
        # SDF writes some settings either way: <noise type="gaussian"> or <noise><type>.
        for attribute, text in child.attrib.items():
            values.setdefault(f'{path}/{attribute}', text.strip())
        if not len(child):
            values[path] = (child.text or '').strip()
    pose_text = values.get('pose', '0 0 0 0 0 0')
    pose = parse_numbers(pose_text, f'sensor {quoted(name)} <pose>')
    if len(pose) != 6:
        raise UrdfError(f'sensor {quoted(name)} <pose> must be six numbers '
                        f'(x y z roll pitch yaw): {quoted(pose_text)}')
    orientation = np.zeros(4)
    mujoco.mju_euler2Quat(orientation, np.array(pose[3:]), 'XYZ')  # URDF's and SDF's rpy
    return SensorBlock(
        link=link, sensor_type=(element.get('type') or '').strip(), name=name,
        update_rate=_number(name, values, 'update_rate', 0.0, minimum=0.0),
        position=tuple(pose[:3]), orientation=tuple(orientation.tolist()),
        values=types.MappingProxyType(values))


def _stripped_texts(element, tag):
    return tuple((child.text or '').strip() for child in element.findall(tag))


def read_link_friction(root):
    """Return {link: (mu1, mu2)} from <gazebo reference="link"> blocks."""
    friction = {}
    link_names = {link.get('name') for link in root.findall('link')}
    for block in root.findall('gazebo'):
        reference = block.get('reference')
        if reference is None or reference not in link_names:
            continue
        values = {}
        for key in ('mu1', 'mu2'):
            element = block.find(key)
            if element is None:
                continue
            text = element.get('value') if element.get('value') is not None else element.text
            value = parse_numbers(text or '', f"gazebo <{key}> of link '{reference}'")
            if len(value) != 1 or value[0] < 0.0:
                raise UrdfError(
                    f"gazebo <{key}> of link '{reference}' must be one number >= 0: '{text}'")
            values[key] = value[0]
        if values:
            mu1 = values.get('mu1', values.get('mu2'))
            mu2 = values.get('mu2', mu1)
            friction[reference] = (mu1, mu2)
    return friction
