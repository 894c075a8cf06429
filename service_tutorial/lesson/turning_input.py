"""
What the lesson's turning programs take as typed input: its limits, prompts and refusals.

The turning service and action, the clients that prompt for them and the lesson's panel on the
world's web page share these: the top angular velocity of the lesson (1.5707 rad/s), the
largest angle the action turns, the prompts and refusals the lesson's client printed, and the
parsing that applies them.
"""

import math

import rclpy.logging

MAX_ANGULAR_VEL = 1.5707  # rad/s, the lesson's own limit
MAX_ANGLE = 20.0 * math.pi  # rad, ten turns either way
MAX_UINT32 = 2**32 - 1
NOT_A_NUMBER = 'Not a number type number plz !!'
VELOCITY_TOO_HIGH = 'Velocity too high !!'
DURATION_NOT_WHOLE = 'Duration must be a whole number of seconds, 0 or more !!'
DURATION_PROMPT = '> Type turning time duration: '
VELOCITY_PROMPT = '> Type turning angular velocity: '


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


def ask_turning_request(logger, *, read=input, prompts=(DURATION_PROMPT, VELOCITY_PROMPT),
                        parse=parse_turning_request):
    """Prompt for two values (duration, velocity) until parse takes them; EOFError at the end."""
    while True:
        first_text = read(prompts[0])
        velocity_text = read(prompts[1])
        try:
            return parse(first_text, velocity_text)
        except TurningInputError as error:
            logger.error(str(error))


def given_or_asked(given, ask, program):
    """Return what the command line gave, or prompt with ask(logger); None if input ends."""
    if given is not None:
        return given
    # Prompted before rclpy takes over Ctrl-C, so that Ctrl-C at a prompt stops the program.
    try:
        return ask(rclpy.logging.get_logger(program))
    except (EOFError, KeyboardInterrupt):
        print()
        return None


def parse_pair_or_nothing(argv, parser, names, parse, result):
    """
    Read the two positionals names through parse() into options.<result>, None if not given.

    The lesson's clients take both numbers on the command line or prompt for them; a bad
    pair ends the program with argparse's usage line and the reason.
    """
    first, second = names
    options = parser.parse_args(argv)
    values = (getattr(options, first), getattr(options, second))
    if (values[0] is None) != (values[1] is None):
        parser.error(f'give both {first} and {second}, or neither to be prompted')
    setattr(options, result, None)
    if values[0] is not None:
        try:
            setattr(options, result, parse(*values))
        except TurningInputError as error:
            parser.error(str(error))
    return options
