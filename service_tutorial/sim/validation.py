"""
Checks of what callers hand the world, and WorldError, the refusal that names the cause.

Every refusal carries a Reason, so that the ROS side answers it in its own words (a standard
Result code, the lesson's success and status_message) without judging the request again.
"""

import enum
import math

import numpy as np

WORLD_FRAMES = ('', 'world')
SCOPE_SEPARATOR = '::'
MAX_MODEL_NAME_LENGTH = 64
# Longest piece of a caller's text repeated in a refusal.
MAX_QUOTED_LENGTH = 80
# Beyond these magnitudes a model's state is treated as broken, like MuJoCo's own checks.
HUGE_POSITION = 1e8
HUGE_VELOCITY = 1e5
HUGE_ACCELERATION = 1e10


class Reason(enum.Enum):
    """Why the world refuses a request."""

    INVALID = 'a value out of range'
    NO_WORLD = 'no world is loaded'
    NO_SUCH_MODEL = 'no such model'
    NAME_INVALID = 'the name is invalid'
    NAME_TAKEN = 'the name is taken'
    NAMESPACE_INVALID = 'the namespace is invalid'
    UNKNOWN_FRAME = 'the reference frame is unknown'
    BAD_POSE = 'the pose is invalid'
    NO_RESOURCE = 'the file is not there, or not one a request may name'
    UNSUPPORTED_FORMAT = 'the format is not one the world reads'
    NOT_PARSEABLE = 'the text does not parse'
    MISSING_ASSET = 'a file it names is missing'
    REFUSED_ASSET = 'a file it names may not be read'
    UNSUPPORTED_CONTENT = 'it holds what the world does not take there'
    DOES_NOT_COMPILE = 'MuJoCo does not compile it'
    CANNOT_SIMULATE = 'MuJoCo cannot simulate it'
    MODEL_REFUSED = "one of a world's models is refused"


class WorldError(ValueError):
    """A request the world refuses; str(error) names the cause and the value, reason says why."""

    reason = Reason.INVALID

    def __init__(self, message, reason=None):
        """Refuse with message, for reason (the class's own if None)."""
        super().__init__(message)
        if reason is not None:
            self.reason = reason


class DescriptionError(WorldError):
    """A robot description the world refuses: it does not parse, or MuJoCo will not build it."""

    reason = Reason.NOT_PARSEABLE


class AssetError(DescriptionError):
    """A description refused for a file it names: missing, or one it may not have read."""

    def __init__(self, message, *, missing=False):
        """Refuse with message; missing: the file is allowed but cannot be had."""
        super().__init__(message, Reason.MISSING_ASSET if missing else Reason.REFUSED_ASSET)


def quoted(text):
    """Return user text in quotes for a message: control characters escaped, long text cut."""
    shown = text[:MAX_QUOTED_LENGTH]
    if not shown.isprintable():  # one C call for the usual text, not a step per character
        shown = ''.join(character if character.isprintable() else repr(character)[1:-1]
                        for character in shown)
    if len(text) > MAX_QUOTED_LENGTH:
        return f"'{shown}...' ({len(text)} characters)"
    return f"'{shown}'"


def vector(values, size, what):
    """Return values as a finite float array of the given size, or refuse them."""
    try:
        array = np.array(values, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise WorldError(f'{what} is not a vector of {size} numbers: {values!r}') from None
    if array.shape != (size,):
        raise WorldError(f'{what} must have {size} elements, not {array.size}')
    # The checks of a few numbers go on Python floats: a NumPy call each costs several times
    # as much, and every spawn and state a client sets is checked.
    if not all(map(math.isfinite, array.tolist())):
        raise WorldError(f'{what} contains NaN or infinity: {array.tolist()}')
    return array


def unit_quaternion(values, what='orientation'):
    """Return a (w, x, y, z) quaternion scaled to unit length; refuse a zero one."""
    components = vector(values, 4, what).tolist()
    largest = max(map(abs, components))
    if largest == 0.0:
        raise WorldError(f'{what} quaternion is zero: {components}')
    # Scaled first, so that neither huge nor tiny components overflow or underflow the norm.
    scaled = [component / largest for component in components]
    norm = math.hypot(*scaled)
    return np.array([component / norm for component in scaled])


def position(values, what='position'):
    """Return a position of three finite numbers within HUGE_POSITION of the origin."""
    array = vector(values, 3, what)
    if max(map(abs, array.tolist())) >= HUGE_POSITION:
        raise WorldError(f'{what} must stay below {HUGE_POSITION:g} m in magnitude: '
                         f'{array.tolist()}')
    return array


def check_velocity(array, what, model_name):
    """Refuse a linear or angular velocity of a model that reaches HUGE_VELOCITY."""
    if np.abs(array).max() >= HUGE_VELOCITY:
        raise WorldError(f'{what} of model {model_name!r} must stay below {HUGE_VELOCITY:g} '
                         f'in magnitude: {array.tolist()}')


def finite_number(value, what):
    """Return value as a finite float, or refuse it."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise WorldError(f'{what} is not a number: {value!r}') from None
    if not math.isfinite(number):
        raise WorldError(f'{what} is NaN or infinite: {number}')
    return number


def bounded(array, limit):
    """Return True if every value is finite and smaller than limit in magnitude."""
    # No value is larger than the root of the sum of squares, which one BLAS call gives and
    # which is NaN or infinite if any value is: it settles nearly every check of a sane state.
    return (array.size == 0 or float(np.vdot(array, array)) < limit * limit
            or float(np.abs(array).max()) < limit)


def check_model_name(name):
    """Refuse a model name that could not serve as a frame, a prefix or a topic part."""
    if not isinstance(name, str) or not name:
        raise WorldError('model name must not be empty', Reason.NAME_INVALID)
    shown = quoted(name)
    problem = None
    if len(name) > MAX_MODEL_NAME_LENGTH:
        problem = f'is longer than {MAX_MODEL_NAME_LENGTH} characters'
    elif SCOPE_SEPARATOR in name:
        problem = f"must not contain '{SCOPE_SEPARATOR}'"
    elif '/' in name:
        problem = "must not contain '/'"
    elif any(character.isspace() for character in name):
        problem = 'must not contain whitespace'
    elif not name.isprintable() or any(character in '"\'<>&\\' for character in name):
        problem = 'contains a character that is not allowed'
    elif name in WORLD_FRAMES:
        problem = 'is reserved for the world frame'
    if problem is not None:
        raise WorldError(f'model name {shown} {problem}', Reason.NAME_INVALID)


def non_negative_number(value, what):
    """Return value as a finite float of 0 or more, or refuse it."""
    number = finite_number(value, what)
    if number < 0.0:
        raise WorldError(f'{what} must not be negative: {number}')
    return number
