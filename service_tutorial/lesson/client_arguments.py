"""
What the lesson's one-off clients share on their command line: their arguments and --timeout.

Their main() is node_main.run_node, as every executable's here.
"""

import argparse

from service_tutorial.lesson.model_services import DEFAULT_TIMEOUT


def parse_client_arguments(argv, prog, description, add_arguments=None):
    """Parse a world service client's command line: its own arguments, then --timeout."""
    parser = argparse.ArgumentParser(prog=prog, description=description)
    if add_arguments is not None:
        add_arguments(parser)
    parser.add_argument('--timeout', type=float, default=DEFAULT_TIMEOUT,
                        help='seconds to wait for the service and its answer '
                             '(default: %(default)s)')
    return parser.parse_args(argv)
