"""Checks of what callers hand the world, and WorldError, the refusal that names the cause."""

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


class WorldError(ValueError):
    """A request the world refuses; str(error) names the cause and the offending value."""


class DescriptionError(WorldError):
    """A robot description the world refuses: it does not parse, or MuJoCo will not build it."""


class AssetError(DescriptionError):
    """A description refused for a file it names: missing, or one it may not have read."""

    def __init__(self, message, *, missing=False):
        """Refuse with message; missing: the file is allowed but cannot be had."""
        super().__init__(message)
        self.missing = missing


def quoted(text):
    """Return user text in quotes for a message: control characters escaped, long text cut."""
    shown = text[:MAX_QUOTED_LENGTH]
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
    if not np.isfinite(array).all():
        raise WorldError(f'{what} contains NaN or infinity: {array.tolist()}')
    return array


def unit_quaternion(values, what='orientation'):
    """Return a (w, x, y, z) quaternion scaled to unit length; refuse a zero one."""
    quaternion = vector(values, 4, what)
    largest = np.abs(quaternion).max()
    if largest == 0.0:
        raise WorldError(f'{what} quaternion is zero: {quaternion.tolist()}')
    # Scaled first, so that neither huge nor tiny components overflow or underflow the norm.
    quaternion = quaternion / largest
    return quaternion / np.linalg.norm(quaternion)


def position(values, what='position'):
    """Return a position of three finite numbers within HUGE_POSITION of the origin."""
    array = vector(values, 3, what)
    if np.abs(array).max() >= HUGE_POSITION:
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
        raise WorldError('model name must not be empty')
    shown = quoted(name)
    if len(name) > MAX_MODEL_NAME_LENGTH:
        raise WorldError(f'model name {shown} is longer than {MAX_MODEL_NAME_LENGTH} '
                         'characters')
    if SCOPE_SEPARATOR in name:
        raise WorldError(f"model name {shown} must not contain '{SCOPE_SEPARATOR}'")
    if '/' in name:
        raise WorldError(f"model name {shown} must not contain '/'")
    if any(character.isspace() for character in name):
        raise WorldError(f'model name {shown} must not contain whitespace')
    if not name.isprintable() or any(character in '"\'<>&\\' for character in name):
        raise WorldError(f'model name {shown} contains a character that is not allowed')
    if name in WORLD_FRAMES:
        raise WorldError(f'model name {shown} is reserved for the world frame')


def non_negative_number(value, what):
    """Return value as a finite float of 0 or more, or refuse it."""
    number = finite_number(value, what)
    if number < 0.0:
        raise WorldError(f'{what} must not be negative: {number}')
    return number
