"""ROS naming rules the world node applies to a spawn request; the simulation knows none."""

import re

from rclpy.exceptions import InvalidTopicNameException
from rclpy.impl.implementation_singleton import rclpy_implementation as _rclpy
from rclpy.validate_full_topic_name import validate_full_topic_name
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import Reason
from service_tutorial.sim.validation import WorldError

# Leaves room for the topic names under it within the DDS limit of about 250 characters.
MAX_NAMESPACE_LENGTH = 200
# A part of a ROS name between slashes: an ASCII letter or underscore, then letters, digits, _.
_TOKEN = '[A-Za-z_][A-Za-z0-9_]*'
_PATH = re.compile(f'{_TOKEN}(?:/{_TOKEN})*')


def normalise_namespace(namespace):
    """Return a robot namespace as '' or '/a/b', or refuse what ROS would refuse."""
    namespace = (namespace or '').strip()
    tokens = [token for token in namespace.split('/') if token]
    for token in tokens:
        if not re.fullmatch(_TOKEN, token):
            raise WorldError(f'robot namespace {quoted(namespace)} is not a valid ROS '
                             f'namespace: its part {quoted(token)} must start with a letter '
                             'or underscore and hold only ASCII letters, digits and '
                             'underscores', Reason.NAMESPACE_INVALID)
    normalised = '/' + '/'.join(tokens) if tokens else ''
    if len(normalised) > MAX_NAMESPACE_LENGTH:
        raise WorldError(f'robot namespace {quoted(namespace)} is longer than '
                         f'{MAX_NAMESPACE_LENGTH} characters', Reason.NAMESPACE_INVALID)
    return normalised


def topic_prefix(namespace):
    """Return what goes before a topic's relative name in a normalised namespace."""
    return namespace + '/' if namespace else ''


def plugin_topic(block, topic, *, robot_namespace='', ros1_tag=None):
    """
    Return the topic a Gazebo plugin block's topic ends up on, as gazebo_ros would put it.

    topic is the plugin's own name for it: 'cmd_vel', or '~/out' for one under the plugin's
    node. A ROS 1 block names it in ros1_tag (commandTopic, topicName...) instead. The
    namespace is the spawn request's robot_namespace if it has one (gazebo_ros replaces the
    plugin's namespace with it), else the block's <ros><namespace>, else its ROS 1
    <robotNamespace>; then the first <remapping> or <argument> 'from:=to' whose expanded
    'from' is this topic moves it. A name relative to the root stays relative, so that a
    remapping of the world node still applies to it.
    """
    namespace = robot_namespace or _block_namespace(block)
    node = block.name or 'plugin'
    if ros1_tag is not None and block.text(ros1_tag):
        topic = block.text(ros1_tag)
    name = _expand(topic, namespace, node, block)
    for rule in block.ros_remappings + block.ros_arguments:
        source, separator, target = rule.partition(':=')
        if separator and _expand(source.strip(), namespace, node, block) == name:
            name = _expand(target.strip(), namespace, node, block)
            break
    return name


def _block_namespace(block):
    """Return the namespace a plugin block asks for itself, normalised."""
    written = block.ros_namespace or block.text('robotNamespace', '')
    try:
        return normalise_namespace(written)
    except WorldError:
        raise WorldError(f'plugin {quoted(block.name)} has namespace {quoted(written)}, '
                         'which is not a valid ROS namespace') from None


def _expand(name, namespace, node, block):
    """Expand a topic name the way rcl does: '~/' under the node, relative under namespace."""
    if name.startswith('~/') or name == '~':
        expanded = '/'.join(part for part in (namespace, node, name[2:]) if part)
    elif name.startswith('/'):
        expanded = name
    else:
        expanded = topic_prefix(namespace) + name
    if not _PATH.fullmatch(expanded.strip('/')):
        raise WorldError(f'plugin {quoted(block.name)} names topic {quoted(name)}, which is '
                         'not a valid ROS topic name')
    return expanded


def check_topic(node, model_name, topic):
    """Refuse a topic name that the node could not make, as the world refuses a model."""
    try:
        validate_full_topic_name(node.resolve_topic_name(topic))
    except (InvalidTopicNameException, _rclpy.RCLError) as error:
        reason = str(error).partition(', at /')[0]  # rcl's source file says nothing more
        raise WorldError(f'topic {quoted(topic)} of model {quoted(model_name)} is not a valid '
                         f'ROS topic name here: {reason}') from None
