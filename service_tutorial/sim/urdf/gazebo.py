"""
The <gazebo> extension blocks of a URDF: per-link surface settings and plugin blocks.

A plugin block is kept as written (its parameters, its <ros> settings): the plugin module
parses what the simulation needs, and a ROS face reads its topic settings from the same block.
"""

from dataclasses import dataclass
import types

from service_tutorial.sim.urdf.hardened_xml import parse_numbers
from service_tutorial.sim.urdf.hardened_xml import UrdfError


@dataclass(frozen=True)
class PluginBlock:
    """One <plugin> of a robot-wide <gazebo> block, as the URDF writes it."""

    filename: str
    name: str
    parameters: types.MappingProxyType  # child tag -> its elements' texts, in document order
    ros_namespace: str = ''  # <ros><namespace>, stripped
    ros_remappings: tuple = ()  # <ros><remapping> texts, stripped
    ros_arguments: tuple = ()   # <ros><argument> texts, stripped

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
        for plugin in gazebo.findall('plugin'):
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
            blocks.append(PluginBlock(
                filename=plugin.get('filename') or '', name=plugin.get('name') or '',
                parameters=types.MappingProxyType(
                    {tag: tuple(texts) for tag, texts in parameters.items()}),
                **settings))
    return tuple(blocks)


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
