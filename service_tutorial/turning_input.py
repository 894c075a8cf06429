"""
The lesson's turning limits, and the parsing of a typed duration and velocity that applies them.

Shared by the lesson's turning programs and by the world node's web page, which may not import
the lesson: the top angular velocity of the lesson (1.5707 rad/s), the largest angle the action
turns, the refusals the lesson's client printed, and the parsing that gives them.
"""

import math

MAX_ANGULAR_VEL = 1.5707  # rad/s, the lesson's own limit
MAX_ANGLE = 20.0 * math.pi  # rad, ten turns either way
MAX_UINT32 = 2**32 - 1
NOT_A_NUMBER = 'Not a number type number plz !!'
VELOCITY_TOO_HIGH = 'Velocity too high !!'
DURATION_NOT_WHOLE = 'Duration must be a whole number of seconds, 0 or more !!'


class TurningInputError(ValueError):
    """A typed duration or velocity that cannot go into the request."""


def typed_numbers(*texts):
    """Return the typed texts as finite numbers, or raise TurningInputError(NOT_A_NUMBER)."""
    try:
        numbers = [float(text) for text in texts]
    except ValueError:
        raise TurningInputError(NOT_A_NUMBER) from None
    if not all(math.isfinite(number) for number in numbers):
        raise TurningInputError(NOT_A_NUMBER)
    return numbers


def parse_turning_request(duration_text, velocity_text, *, max_angular_vel=MAX_ANGULAR_VEL):
    """Turn the typed duration and velocity into (time_duration, angular_vel) or raise."""
    duration, velocity = typed_numbers(duration_text, velocity_text)
    if duration < 0 or duration != int(duration) or duration > MAX_UINT32:
        raise TurningInputError(DURATION_NOT_WHOLE)
    if abs(velocity) > max_angular_vel:
        raise TurningInputError(VELOCITY_TOO_HIGH)
    return int(duration), velocity
