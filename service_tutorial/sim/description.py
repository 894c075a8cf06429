"""
What the URDF builder and the plugins both read a robot description with.

sim/urdf/ turns a URDF into a MuJoCo spec and sim/plugins/ read their own blocks of the same
file; both refuse what they cannot use with UrdfError and read numbers with parse_numbers.
The geom groups say which geoms a robot shows and which a laser sees.
"""

import math

from service_tutorial.sim.validation import quoted

VISUAL_GROUP = 1  # what the robot looks like
COLLISION_GROUP = 3  # what it collides with, and what lasers see


class UrdfError(ValueError):
    """A URDF the loader refuses; the message names the cause and the offending value."""


def parse_numbers(text, what):
    """Return the numbers of a whitespace- or comma-separated text; refuse NaN and infinity."""
    try:
        values = [float(token) for token in text.replace(',', ' ').split()]
    except ValueError:
        raise UrdfError(f'{what} is not a number: {quoted(text)}') from None
    if not all(math.isfinite(value) for value in values):
        raise UrdfError(f'{what} contains NaN or infinity: {quoted(text)}')
    return values
