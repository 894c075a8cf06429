"""
SDF's elements as the reader takes them: values with their checks, and what is not simulated.

Every element of SDF 1.11 the reader meets is one of three kinds, by the element that holds
it: read (it is simulated), quiet (it has no physics effect in gz-sim either, or does here
what the world does anyway: a <scene>, a <light>, a <gui>, gz-sim's own world systems), or
not simulated: named once in the file's note, and refused when a request asks for that
(fail_on_unsupported_element). Values are read into numbers here, each refused with a
DescriptionError that names the element when it is not what SDF says it is, or is absurd.
"""

import math

from service_tutorial.sim.plugins import gz_system
from service_tutorial.sim.validation import DescriptionError
from service_tutorial.sim.validation import quoted

# Values no model can have, refused as absurd.
MAX_COORDINATE = 1e6  # m, a pose's position
MAX_ANGLE = 1e4  # rad, a pose's angle
MAX_MASS = 1e9  # kg
MAX_INERTIA = 1e12  # kg m^2
MAX_SCALE = 1e6  # a mesh's scale
# Per element, the children the reader reads; and those accepted without effect.
READ = {
    'world': ('model', 'include', 'physics', 'gravity', 'frame', 'plugin',
              'spherical_coordinates'),
    'physics': ('max_step_size',),
    'model': ('static', 'self_collide', 'pose', 'link', 'joint', 'model', 'include', 'frame',
              'plugin'),
    'include': ('uri', 'name', 'static', 'pose', 'placement_frame'),
    'link': ('gravity', 'self_collide', 'pose', 'inertial', 'collision', 'visual', 'kinematic',
             'sensor'),
    'inertial': ('mass', 'pose', 'inertia'),
    'collision': ('pose', 'geometry', 'surface'),
    'visual': ('pose', 'geometry', 'material', 'transparency'),
    'geometry': ('box', 'sphere', 'cylinder', 'capsule', 'ellipsoid', 'plane', 'mesh', 'empty'),
    'mesh': ('uri', 'scale'),
    'joint': ('parent', 'child', 'pose', 'axis', 'axis2'),
    'axis': ('xyz', 'limit', 'dynamics', 'use_parent_model_frame'),
    'limit': ('lower', 'upper', 'effort', 'velocity'),
    'dynamics': ('damping', 'friction', 'spring_reference', 'spring_stiffness'),
    'frame': ('pose',),
    'surface': ('friction',),
}
QUIET = {
    'world': ('gui', 'scene', 'light', 'magnetic_field', 'atmosphere', 'wind', 'audio'),
    'physics': ('real_time_factor', 'real_time_update_rate', 'max_contacts', 'ode', 'bullet',
                'simbody', 'dart'),
    'model': ('allow_auto_disable', 'enable_wind'),
    'link': ('enable_wind', 'must_be_base_link', 'audio_sink', 'audio_source', 'light',
             'projector', 'particle_emitter'),
    'collision': ('laser_retro', 'max_contacts'),
    'visual': ('cast_shadows', 'laser_retro', 'meta', 'visibility_flags', 'plugin'),
    'joint': ('physics',),
    'axis': ('initial_position',),
    'limit': ('stiffness', 'dissipation'),
    'surface': ('bounce', 'contact', 'soft_contact'),
}
# gz-sim's own world systems: they do what this world does anyway, so they are accepted.
WORLD_SYSTEMS = ('physics', 'sensors', 'imu', 'scene-broadcaster', 'user-commands', 'contact',
                 'navsat', 'forcetorque', 'magnetometer', 'air-pressure', 'altimeter')
_TRUE, _FALSE = ('true', '1'), ('false', '0')
# Per kind of element, the children that are read or quiet: looked up for each element read.
_KNOWN = {kind: frozenset(READ.get(kind, ()) + QUIET.get(kind, ()))
          for kind in {**READ, **QUIET}}


def is_world_system(filename):
    """Tell whether a <plugin> filename is one of gz-sim's own world systems."""
    return gz_system(filename) in {f'gz-sim-{name}-system' for name in WORLD_SYSTEMS}


class Notes:
    """What a file holds that the world does not simulate: each element once, with its owners."""

    def __init__(self):
        """Start with nothing noted."""
        self.named = {}  # element -> the owners it was met in, in the order first met

    def add(self, element, owner):
        """Note an element ('<sensor>') that is not simulated, met in owner ("link 'l'")."""
        owners = self.named.setdefault(element, [])
        if owner not in owners:
            owners.append(owner)

    def children(self, element, kind, what):
        """Note the children of an element of a kind that are neither read nor quiet."""
        known = _KNOWN.get(kind, frozenset())
        for child in element:
            if isinstance(child.tag, str) and child.tag not in known:
                self.add(f'<{child.tag[:40]}>', what)

    def __iter__(self):
        """Iterate over the notes, one for each element: where it is, or where first and more."""
        for element, owners in self.named.items():
            more = f' and {len(owners) - 1} more' if len(owners) > 1 else ''
            yield f'{element} of {owners[0]}{more}'


def first_child(element, tag):
    """Return an element's first child of a tag, or None."""
    # Not element.find(tag): lxml's path machinery takes twice as long, read hundreds of
    # times for each model.
    return next(element.iterchildren(tag), None)


def child_text(element, tag):
    """Return the stripped text of an element's child, or None if it has none."""
    child = first_child(element, tag)
    return None if child is None else (child.text or '').strip()


def numbers(text, count, what, *, limit=None):
    """Return count finite numbers of a text, each at most limit in magnitude."""
    try:
        values = list(map(float, text.split()))
    except ValueError:
        raise DescriptionError(f'{what} is not {count} numbers: {quoted(text)}') from None
    if len(values) != count:
        raise DescriptionError(f'{what} must be {count} numbers, not {len(values)}: '
                               f'{quoted(text)}')
    if not all(map(math.isfinite, values)):
        raise DescriptionError(f'{what} holds NaN or infinity: {quoted(text)}')
    if limit is not None and max(map(abs, values), default=0.0) > limit:
        raise DescriptionError(f'{what} is absurd, beyond {limit:g} in magnitude: '
                               f'{quoted(text)}')
    return values


def number(element, tag, default, what, *, minimum=None, maximum=None, infinite=False):
    """
    Return the number of an element's child, or default if it has none.

    minimum and maximum bound it (inclusive); infinite: 'inf' and '-inf' are taken too.
    """
    text = child_text(element, tag)
    if text is None or text == '':
        return default
    shown = f'{what} <{tag}>'
    try:
        value = float(text)
    except ValueError:
        raise DescriptionError(f'{shown} is not a number: {quoted(text)}') from None
    if math.isnan(value) or (math.isinf(value) and not infinite):
        raise DescriptionError(f'{shown} is NaN or infinite: {quoted(text)}')
    if (minimum is not None and value < minimum) or (maximum is not None and value > maximum):
        low = '' if minimum is None else f'at least {minimum:g}'
        high = '' if maximum is None else f'at most {maximum:g}'
        raise DescriptionError(f'{shown} must be {" and ".join(filter(None, (low, high)))}: '
                               f'{quoted(text)}')
    return value


def boolean(element, tag, default, what):
    """Return the SDF boolean of an element's child (true, false, 1, 0), or default."""
    text = child_text(element, tag)
    if text is None or text == '':
        return default
    if text.lower() in _TRUE:
        return True
    if text.lower() in _FALSE:
        return False
    raise DescriptionError(f'{what} <{tag}> is not true or false: {quoted(text)}')


def name_of(element, what):
    """Return an element's name attribute, refusing none and one SDF does not allow."""
    name = element.get('name')
    if not name or not name.strip():
        raise DescriptionError(f'a <{element.tag}> in {what} has no name')
    if len(name) > 256 or not name.isprintable() or name.startswith('__') and \
            name.endswith('__'):
        raise DescriptionError(f'{element.tag} name {quoted(name)} in {what} is not allowed')
    return name
