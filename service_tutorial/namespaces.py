"""
ROS namespaces of the models' topics: checked by the world node before anything is spawned.

The simulation knows nothing of namespaces; a spawn request's robot_namespace only decides
where the model's topics go, so the node refuses what ROS would refuse before it asks the
world for anything.
"""

# The core's way of quoting a caller's text in a refusal: control characters escaped, long
# text cut.
from service_tutorial.world import _quoted as quoted

# Leaves room for the topic names under it within the DDS limit of about 250 characters.
MAX_NAMESPACE_LENGTH = 200


class NamespaceError(ValueError):
    """A robot namespace ROS would refuse; str(error) names it and says why."""


def normalise_namespace(namespace):
    """Return a robot namespace as '' or '/a/b', or raise NamespaceError if ROS would refuse it."""
    namespace = (namespace or '').strip()
    tokens = [token for token in namespace.split('/') if token]
    for token in tokens:
        if not (token[0].isalpha() or token[0] == '_') or not all(
                character.isalnum() or character == '_' for character in token) or (
                not token.isascii()):
            raise NamespaceError(f'robot namespace {quoted(namespace)} is not a valid ROS '
                                 f'namespace: its part {quoted(token)} must start with a '
                                 'letter or underscore and hold only ASCII letters, digits '
                                 'and underscores')
    normalised = '/' + '/'.join(tokens) if tokens else ''
    if len(normalised) > MAX_NAMESPACE_LENGTH:
        raise NamespaceError(f'robot namespace {quoted(namespace)} is longer than '
                             f'{MAX_NAMESPACE_LENGTH} characters')
    return normalised


def topic_prefix(namespace):
    """Return what goes before a topic's relative name in a normalised namespace."""
    return namespace + '/' if namespace else ''
