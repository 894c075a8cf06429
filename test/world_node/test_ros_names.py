"""The ROS namespace rules the world node applies to a spawn request, without ROS running."""

import types

import pytest
from service_tutorial.sim.urdf.gazebo import PluginBlock
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.ros_names import normalise_namespace, plugin_topic, topic_prefix


def test_namespaces_are_normalised():
    assert normalise_namespace('') == ''
    assert normalise_namespace(None) == ''
    assert normalise_namespace('robots/tiny/') == '/robots/tiny'
    assert normalise_namespace('/_robots/tiny_1/') == '/_robots/tiny_1'
    assert topic_prefix('/robots/tiny') + 'cmd_vel' == '/robots/tiny/cmd_vel'
    assert topic_prefix('') + 'cmd_vel' == 'cmd_vel'


def test_namespaces_ros_would_refuse_are_refused():
    for namespace, message in [('bad name', 'not a valid ROS namespace'),
                               ('robôt', "its part 'robôt' must start with a letter"),
                               ('a/2b', "its part '2b' must start with a letter"),
                               ('n' * 201, 'longer than 200 characters')]:
        with pytest.raises(WorldError, match=message):
            normalise_namespace(namespace)


@pytest.mark.parametrize('namespace, message', [
    ('1robot', "robot namespace '1robot' is not a valid ROS namespace: its part '1robot' must "
               'start with a letter or underscore and hold only ASCII letters, digits and '
               'underscores'),
    ('my robot', "robot namespace 'my robot' is not a valid ROS namespace: its part 'my robot' "
                 'must start with a letter or underscore and hold only ASCII letters, digits '
                 'and underscores'),
    ('n' * 300, f"robot namespace '{'n' * 80}...' (300 characters) is longer than 200 "
                'characters'),
])
def test_a_refusal_names_the_namespace_and_why(namespace, message):
    with pytest.raises(WorldError) as refusal:
        normalise_namespace(namespace)
    assert str(refusal.value) == message


def block(name='diff_drive', namespace='', remappings=(), arguments=(), **parameters):
    """Return a plugin block as the URDF loader keeps it."""
    return PluginBlock(
        filename='libgazebo_ros_plugin.so', name=name,
        parameters=types.MappingProxyType({tag: (text,) for tag, text in parameters.items()}),
        ros_namespace=namespace, ros_remappings=tuple(remappings), ros_arguments=tuple(arguments))


@pytest.mark.parametrize('plugin, topic, robot_namespace, expected', [
    (block(), 'cmd_vel', '', 'cmd_vel'),
    (block(namespace='/bot'), 'cmd_vel', '', '/bot/cmd_vel'),
    (block(namespace='bot'), 'cmd_vel', '', '/bot/cmd_vel'),
    (block(name='laser'), '~/out', '', 'laser/out'),
    (block(name='laser', remappings=['~/out:=scan']), '~/out', '', 'scan'),
    (block(name='laser', namespace='/bot', remappings=['~/out:=scan']), '~/out', '',
     '/bot/scan'),
    (block(remappings=['cmd_vel:=cmd']), 'cmd_vel', '', 'cmd'),
    (block(namespace='/bot', remappings=['cmd_vel:=cmd']), 'cmd_vel', '', '/bot/cmd'),
    (block(), 'cmd_vel', '/tb2', '/tb2/cmd_vel'),
    # gazebo_ros replaces the plugin's namespace with the spawn request's.
    (block(namespace='/bot'), 'cmd_vel', '/tb2', '/tb2/cmd_vel'),
    (block(name='laser', namespace='/bot', remappings=['~/out:=/scan']), '~/out', '/tb2',
     '/scan'),
    (block(name='laser', arguments=['~/out:=scan']), '~/out', '/tb2', '/tb2/scan'),
    (block(remappings=['odom:=odometry']), 'cmd_vel', '', 'cmd_vel'),
])
def test_plugin_topics_land_where_gazebo_ros_puts_them(plugin, topic, robot_namespace,
                                                       expected):
    assert plugin_topic(plugin, topic, robot_namespace=robot_namespace) == expected


@pytest.mark.parametrize('plugin, tag, robot_namespace, expected', [
    (block(topicName='/scan'), 'topicName', '/tb2', '/scan'),
    (block(topicName='imu/data'), 'topicName', '/tb2', '/tb2/imu/data'),
    (block(commandTopic='cmd_vel'), 'commandTopic', '', 'cmd_vel'),
    (block(commandTopic='base/cmd_vel', robotNamespace='robot1'), 'commandTopic', '',
     '/robot1/base/cmd_vel'),
    (block(robotNamespace='robot1'), 'commandTopic', '/tb2', '/tb2/cmd_vel'),
])
def test_ros1_topic_tags_and_robot_namespace(plugin, tag, robot_namespace, expected):
    assert plugin_topic(plugin, 'cmd_vel', robot_namespace=robot_namespace,
                        ros1_tag=tag) == expected


@pytest.mark.parametrize('plugin, message', [
    (block(commandTopic='cmd vel'), "plugin 'diff_drive' names topic 'cmd vel', which is not a "
                                    'valid ROS topic name'),
    (block(remappings=['cmd_vel:=2fast']), "plugin 'diff_drive' names topic '2fast'"),
    (block(namespace='1bot'), "plugin 'diff_drive' has namespace '1bot', which is not a valid "
                              'ROS namespace'),
])
def test_bad_plugin_topics_are_refused_by_name(plugin, message):
    with pytest.raises(WorldError) as error:
        plugin_topic(plugin, 'cmd_vel', ros1_tag='commandTopic')
    assert str(error.value).startswith(message)
