"""The ROS namespace rules the world node applies to a spawn request, without ROS running."""

import pytest
from service_tutorial.ros_names import normalise_namespace
from service_tutorial.sim.validation import WorldError


def test_namespaces_are_normalised():
    assert normalise_namespace('') == ''
    assert normalise_namespace(None) == ''
    assert normalise_namespace('robots/tiny/') == '/robots/tiny'
    assert normalise_namespace('/_robots/tiny_1/') == '/_robots/tiny_1'


def test_namespaces_ros_would_refuse_are_refused():
    for namespace, message in [('bad name', 'not a valid ROS namespace'),
                               ('robôt', "its part 'robôt' must start with a letter"),
                               ('a/2b', "its part '2b' must start with a letter"),
                               ('n' * 201, 'longer than 200 characters')]:
        with pytest.raises(WorldError, match=message):
            normalise_namespace(namespace)
