"""
The parameters of a gz-sim system's <plugin> block, read with gz's defaults, free of ROS.

A system reads each parameter by its tag, the last one written when a tag is repeated (a
repeated one, <left_joint>, is read as a list); one that is not there takes gz's default. What
gz-sim would take and mis-simulate is refused here with UrdfError, naming the system, the tag
and the text: a number that is not one or is NaN or infinite, a value beyond its bounds (a
negative radius, an absurd rate), a frame tf2 could not name. A <topic> that gz-transport
cannot make valid gives way to the system's default, as gz-sim's validTopic does, and is named
in a note.
"""

import math

from service_tutorial.sim.description import frame_id
from service_tutorial.sim.description import MAX_UPDATE_RATE
from service_tutorial.sim.description import parse_numbers
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.plugins.gz_names import valid_topic
from service_tutorial.sim.validation import quoted

_TRUE, _FALSE = ('true', '1'), ('false', '0')


class GzParameters:
    """Reads one system's parameters from its PluginBlock, collecting notes as it goes."""

    def __init__(self, block, title):
        """Read block, the system named title in refusals ('DiffDrive')."""
        self.block = block
        self.title = title
        self.notes = []

    def has(self, tag):
        """Tell whether the block writes a tag."""
        return tag in self.block.parameters

    def text(self, tag, default=None):
        """Return the last text written for a tag, or default."""
        return self.block.text(tag, default)

    def texts(self, tag):
        """Return the texts of a repeated tag, in document order."""
        return self.block.texts(tag)

    def number(self, tag, default, *, minimum=-math.inf, maximum=math.inf, above=None):
        """Return a tag's number within [minimum, maximum] (and above `above`), or default."""
        text = self.text(tag)
        if text is None:
            return default
        return self.parse(text, tag, minimum=minimum, maximum=maximum, above=above)

    def parse(self, text, tag, *, minimum=-math.inf, maximum=math.inf, above=None):
        """Return the number a text of a tag holds, refusing what is not one or out of bounds."""
        what = f'{self.title} <{tag}>'
        values = parse_numbers(text, what)  # refuses NaN and infinity
        if len(values) != 1:
            raise UrdfError(f'{what} must be one number: {quoted(text)}')
        value = values[0]
        if value < minimum or value > maximum or (above is not None and value <= above):
            bounds = [f'above {above:g}' if above is not None else '',
                      f'at least {minimum:g}' if minimum > -math.inf and above is None else '',
                      f'at most {maximum:g}' if maximum < math.inf else '']
            raise UrdfError(f'{what} must be {" and ".join(filter(None, bounds))}: '
                            f'{quoted(text)}')
        return value

    def rate(self, tag, default):
        """Return a frequency in Hz (0 or less: every step, as gz has it), at most the limit."""
        return self.number(tag, default, maximum=MAX_UPDATE_RATE)

    def vector(self, tag, default):
        """Return a tag's three finite numbers, or default."""
        text = self.text(tag)
        if text is None:
            return default
        values = parse_numbers(text, f'{self.title} <{tag}>')
        if len(values) != 3:
            raise UrdfError(f'{self.title} <{tag}> must be three numbers: {quoted(text)}')
        return tuple(values)

    def flag(self, tag, default):
        """Return an SDF boolean (true, false, 1, 0), or default."""
        text = self.text(tag)
        if text is None:
            return default
        if text.lower() in _TRUE + _FALSE:
            return text.lower() in _TRUE
        raise UrdfError(f'{self.title} <{tag}> must be true or false: {quoted(text)}')

    def frame(self, tag):
        """Return a frame a tag names, as tf2 takes it, or None if the block names none."""
        text = self.text(tag)
        if not text:
            return None
        return frame_id(text, f'{self.title} <{tag}>')

    def topic(self, tag):
        """Return the gz topic a tag names, made valid; None (named in a note) if it cannot be."""
        text = self.text(tag)
        if text is None:
            return None
        topic = valid_topic(text)
        if topic is None:
            self.notes.append(f'{self.title} <{tag}> {quoted(text)} is no valid gz topic; the '
                              "system's default is used, as gz-sim does")
        return topic

    def joints(self, tag, robot, *, required=True):
        """Return the joints a repeated tag names, each a moving joint of the robot."""
        names = tuple(dict.fromkeys(self.texts(tag)))
        if required and not names:
            raise UrdfError(f'{self.title} names no <{tag}>')
        kinds = {joint.name: joint.type for joint in robot.joints}
        for name in names:
            if name not in kinds:
                raise UrdfError(f'{self.title} <{tag}> {quoted(name)} is not a joint of the '
                                'robot')
            if kinds[name] in ('fixed', 'floating', 'planar', 'ball'):
                raise UrdfError(f'{self.title} <{tag}> {quoted(name)} is a {kinds[name]} '
                                'joint, which it cannot drive')
        return names
