"""ROS naming rules the world node applies to a spawn request; the simulation knows none."""

from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WorldError

# Leaves room for the topic names under it within the DDS limit of about 250 characters.
MAX_NAMESPACE_LENGTH = 200


def normalise_namespace(namespace):
    """Return a robot namespace as '' or '/a/b', or refuse what ROS would refuse."""
    namespace = (namespace or '').strip()
    tokens = [token for token in namespace.split('/') if token]
    for token in tokens:
        if not (token[0].isalpha() or token[0] == '_') or not all(
                character.isalnum() or character == '_' for character in token) or (
                not token.isascii()):
            raise WorldError(f'robot namespace {quoted(namespace)} is not a valid ROS '
                             f'namespace: its part {quoted(token)} must start with a letter '
                             'or underscore and hold only ASCII letters, digits and '
                             'underscores')
    normalised = '/' + '/'.join(tokens) if tokens else ''
    if len(normalised) > MAX_NAMESPACE_LENGTH:
        raise WorldError(f'robot namespace {quoted(namespace)} is longer than '
                         f'{MAX_NAMESPACE_LENGTH} characters')
    return normalised


def topic_prefix(namespace):
    """Return what goes before a topic's relative name in a normalised namespace."""
    return namespace + '/' if namespace else ''
