"""
What the URDF builder and the plugins both read a robot description with.

sim/urdf/ turns a URDF into a MuJoCo spec and sim/plugins/ read their own blocks of the same
file; both refuse what they cannot use with UrdfError and read numbers with parse_numbers.
The geom groups say which geoms a robot shows and which a laser sees.
"""

import collections
from dataclasses import dataclass
import math

from service_tutorial.sim.validation import quoted

VISUAL_GROUP = 1  # what the robot looks like
COLLISION_GROUP = 3  # what it collides with, and what lasers see
# Values no robot can have, refused when a description is loaded (docs/bad-input.md).
# A shape, a scaled mesh or a drive's wheels larger than this, in metres, in any extent:
MAX_SIZE = 1000.0
# The fastest a sensor may measure or a drive publish, in Hz: real IMUs reach a few kHz, and
# a rate above the physics rate is served at every step, as Gazebo does.
MAX_UPDATE_RATE = 10000.0
MAX_FRAME_ID_LENGTH = 256


class UrdfError(ValueError):
    """A URDF the loader refuses; the message names the cause and the offending value."""


def parse_numbers(text, what):
    """Return the numbers of a whitespace- or comma-separated text; refuse NaN and infinity."""
    # map(), not a comprehension or generator: this reads every number of every robot.
    try:
        values = list(map(float, text.replace(',', ' ').split()))
    except ValueError:
        raise UrdfError(f'{what} is not a number: {quoted(text)}') from None
    if not all(map(math.isfinite, values)):
        raise UrdfError(f'{what} contains NaN or infinity: {quoted(text)}')
    return values


def frame_id(text, what):
    """
    Return a frame id as tf2 takes it, or refuse one that no transform could name.

    One leading slash, which ROS 1 robot files write (/odom), is dropped, as tf2 drops it;
    an id that is empty, has empty parts (//a, a//b, a/), whitespace or control characters
    is refused.
    """
    shown = quoted(text)
    frame = text[1:] if text.startswith('/') else text
    if not frame:
        raise UrdfError(f'{what} must name a frame: {shown}')
    if len(frame) > MAX_FRAME_ID_LENGTH:
        raise UrdfError(f'{what} is longer than {MAX_FRAME_ID_LENGTH} characters: {shown}')
    if '' in frame.split('/'):
        raise UrdfError(f'{what} {shown} is not a valid frame id: it has an empty part '
                        "(a doubled, leading or trailing '/')")
    if not frame.isprintable() or any(character.isspace() for character in frame):
        raise UrdfError(f'{what} {shown} is not a valid frame id: it holds whitespace or '
                        'control characters')
    return frame


def check_update_rate(rate, what):
    """Return an update rate in Hz (0: every step), refusing one above MAX_UPDATE_RATE."""
    if rate > MAX_UPDATE_RATE:
        raise UrdfError(f'{what} must be at most {MAX_UPDATE_RATE:g} Hz: {rate:g}')
    return rate


# A link or joint as a plugin reads it, as yourdfpy's robot has them: its name, and a joint's
# type (revolute, continuous...).
OutlineElement = collections.namedtuple('OutlineElement', ('name', 'type'), defaults=('',))


@dataclass(frozen=True)
class RobotOutline:
    """What a plugin reads of a robot of any format, as yourdfpy's robot has it for a URDF."""

    name: str
    links: tuple  # OutlineElements
    joints: tuple  # OutlineElements, with their types
