"""
The lesson's turning limits, and what its clients say when a typed value breaks one.

The turning service and action, and the clients that prompt for them, share these: the top
angular velocity of the lesson (1.5707 rad/s), the largest angle the action turns, the
prompts and refusals the lesson's client printed, and the parsing that applies them. The
limits and the parsing live in service_tutorial.turning_input, which the world node's web page
uses too; they are named here as well, for the lesson's programs.
"""

import rclpy.logging
from service_tutorial.turning_input import DURATION_NOT_WHOLE, MAX_ANGLE, MAX_ANGULAR_VEL
from service_tutorial.turning_input import MAX_UINT32, NOT_A_NUMBER, parse_turning_request
from service_tutorial.turning_input import TurningInputError, typed_numbers, VELOCITY_TOO_HIGH

__all__ = ['DURATION_NOT_WHOLE', 'MAX_ANGLE', 'MAX_ANGULAR_VEL', 'MAX_UINT32', 'NOT_A_NUMBER',
           'parse_turning_request', 'TurningInputError', 'typed_numbers', 'VELOCITY_TOO_HIGH',
           'DURATION_PROMPT', 'VELOCITY_PROMPT', 'ask_turning_request', 'given_or_asked',
           'parse_pair_or_nothing']

DURATION_PROMPT = '> Type turning time duration: '
VELOCITY_PROMPT = '> Type turning angular velocity: '


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
