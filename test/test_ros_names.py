"""The ROS namespace rules the world node applies to a spawn request, without ROS running."""

import pytest
from service_tutorial.ros_names import normalise_namespace, topic_prefix
from service_tutorial.sim.validation import WorldError


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
