"""Robot namespaces: what the world node accepts, how it writes them, and what it refuses."""

import pytest
from service_tutorial.namespaces import NamespaceError, normalise_namespace, topic_prefix


def test_namespaces_are_written_with_one_leading_slash_and_none_at_the_end():
    assert normalise_namespace('robots/tiny/') == '/robots/tiny'
    assert normalise_namespace('') == '' and normalise_namespace(None) == ''
    assert normalise_namespace(' /robot1 ') == '/robot1'
    assert normalise_namespace('/_robots/tiny_1/') == '/_robots/tiny_1'
    assert topic_prefix('/robots/tiny') + 'cmd_vel' == '/robots/tiny/cmd_vel'
    assert topic_prefix('') + 'cmd_vel' == 'cmd_vel'


def test_namespaces_ros_would_refuse_are_refused():
    for namespace, message in [('robôt', "its part 'robôt' must start with a letter"),
                               ('a/2b', "its part '2b' must start with a letter"),
                               ('bad name', 'not a valid ROS namespace'),
                               ('n' * 201, 'longer than 200 characters')]:
        with pytest.raises(NamespaceError, match=message):
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
    with pytest.raises(NamespaceError) as refusal:
        normalise_namespace(namespace)
    assert str(refusal.value) == message
