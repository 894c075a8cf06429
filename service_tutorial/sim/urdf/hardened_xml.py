"""
Hardened parsing of URDF text, and the checks of its structure made before yourdfpy reads it.

Documents with a DOCTYPE are refused, so external entities and entity-expansion bombs never
reach a parser that would resolve them.
"""

import math

from lxml import etree
from service_tutorial.sim.description import parse_numbers, UrdfError
from service_tutorial.sim.validation import quoted

MAX_MODEL_XML_BYTES = 10 * 1024 * 1024
JOINT_TYPES = ('fixed', 'revolute', 'continuous', 'prismatic', 'floating', 'planar')
XACRO_NAMESPACE = 'http://www.ros.org/wiki/xacro'
_XACRO_ELEMENTS = '{' + XACRO_NAMESPACE + '}*'  # lxml's pattern of every element in it


def parse_model_xml(model_xml):
    """Parse model_xml with a hardened parser and return the <robot> root element."""
    data = model_xml.encode('utf-8') if isinstance(model_xml, str) else bytes(model_xml)
    if len(data) > MAX_MODEL_XML_BYTES:
        raise UrdfError(
            f'model_xml is {len(data)} bytes, more than the limit of {MAX_MODEL_XML_BYTES}')
    if not data.strip():
        raise UrdfError('model_xml is empty')
    if b'\x00' in data:
        # UTF-16 or UTF-32 text would slip past the byte scan for a DOCTYPE below.
        raise UrdfError('model_xml must be UTF-8 text')
    root = parse_xml(data, 'model_xml')
    tag = etree.QName(root).localname
    if tag != 'robot' or etree.QName(root).namespace:
        raise UrdfError(f'model_xml is not URDF: root element is <{tag}>')
    if next(root.iter(_XACRO_ELEMENTS), None) is not None:
        raise UrdfError('model_xml contains xacro macros; run xacro on it first')
    return root


def parse_xml(data, what, *, huge_tree=False):
    """
    Parse XML bytes from an untrusted source and return the root element.

    A DTD is the only way to declare entities; refusing it outright means nothing is ever
    fetched or expanded, whatever a later parser of the same bytes would have done.
    """
    if b'<!DOCTYPE' in data or b'<!ENTITY' in data:
        raise UrdfError(f'{what} contains a DOCTYPE or ENTITY declaration, which is refused')
    parser = etree.XMLParser(
        resolve_entities=False, no_network=True, load_dtd=False, dtd_validation=False,
        huge_tree=huge_tree, remove_comments=True, remove_pis=True)
    try:
        root = etree.fromstring(data, parser)
    except (etree.XMLSyntaxError, ValueError) as error:
        raise UrdfError(f'{what} does not parse as XML: {error}') from None
    if root.getroottree().docinfo.doctype:
        raise UrdfError(f'{what} contains a DOCTYPE declaration, which is refused')
    return root


def check_structure(root):
    """Refuse the structural faults yourdfpy would report with a bare KeyError."""
    if not root.get('name'):
        raise UrdfError('model_xml is not valid URDF: <robot> has no name attribute')
    links = list(root.iterchildren('link'))
    if not links:
        raise UrdfError('model_xml has no <link>')
    link_names = set()
    for link in links:
        _new_name(link, link_names)
    joint_names = set()
    for joint in root.iterchildren('joint'):
        name = _new_name(joint, joint_names)
        for end in ('parent', 'child'):
            element = next(joint.iterchildren(end), None)
            if element is None or not element.get('link'):
                raise UrdfError(f"joint '{name}' has no <{end} link=...>")
        kind = joint.get('type')
        if not kind:
            raise UrdfError(f"joint '{name}' has no type attribute")
        if kind not in JOINT_TYPES:
            raise UrdfError(f"joint '{name}' has unknown type '{kind}'")
        check_numbers(joint, f"joint '{name}'")
    for link in links:
        check_numbers(link, f"link '{link.get('name')}'")
        for geometry in link.iter('geometry'):
            if len(geometry) == 0:
                raise UrdfError(f"link '{link.get('name')}' has an empty <geometry>")


def _new_name(element, names):
    """Return the name of a <link> or <joint>, refusing none and one already in names."""
    name = element.get('name')
    if not name:
        raise UrdfError(f'a <{element.tag}> has no name attribute')
    if name in names:
        raise UrdfError(f"{element.tag} '{name}' is defined twice")
    names.add(name)
    return name


# Attributes that hold numbers, by element, and how many numbers each may hold.
_NUMERIC_ATTRIBUTES = {
    'origin': {'xyz': (3,), 'rpy': (3,)}, 'axis': {'xyz': (3,)},
    'dynamics': {'damping': (1,), 'friction': (1,)},
    'limit': {'lower': (1,), 'upper': (1,), 'effort': (1,), 'velocity': (1,)},
    'mass': {'value': (1,)},
    'inertia': {key: (1,) for key in ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')},
    'box': {'size': (3,)}, 'cylinder': {'radius': (1,), 'length': (1,)},
    'sphere': {'radius': (1,)}, 'mesh': {'scale': (1, 3)}, 'color': {'rgba': (4,)}}


def check_numbers(element, what):
    """Refuse numeric attributes below element that do not hold the numbers they should."""
    for child in element.iter(*_NUMERIC_ATTRIBUTES):
        attributes = child.attrib
        tag = child.tag  # lxml makes a new string at each reading
        for key, counts in _NUMERIC_ATTRIBUTES[tag].items():
            text = attributes.get(key)
            if text is None:
                continue
            # What every robot's numbers pass, without a message made for each; parse_numbers()
            # says what is wrong with the others.
            try:
                values = list(map(float, text.split() if ',' not in text
                                  else text.replace(',', ' ').split()))
            except ValueError:
                values = None
            if values is None or len(values) not in counts or \
                    not all(map(math.isfinite, values)):
                _refuse_numbers(text, counts, f'{what} <{tag} {key}>')


def _refuse_numbers(text, counts, where):
    """Raise the UrdfError that says why text is not the numbers an attribute holds."""
    values = parse_numbers(text, where)
    expected = ' or '.join(str(count) for count in counts)
    raise UrdfError(f'{where} must hold {expected} numbers, not {len(values)}: {quoted(text)}')
