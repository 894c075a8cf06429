"""
The loggers the simulation logs to: `service_tutorial` and the loggers under it.

Their records go up Python's logger hierarchy as usual: to the root logger, where an
application's own logging set-up (or pytest's caplog) reads them, and to the handler a world
node hangs on `service_tutorial`, which passes them on to its rclpy logger and /rosout.
Whether a new logger propagates is up to the logger class installed at the time, and importing
`launch` installs one whose loggers do not (launch.logging); launch_testing's pytest plugin
imports it in every pytest run on a ROS 2 Jazzy install. So core_logger() sets the propagation
of the simulation's loggers itself instead of leaving it to whoever imported what first.
"""

import logging

CORE_LOGGER = 'service_tutorial'


def core_logger(name):
    """Return the logger called name, propagating, as is every logger between it and the root."""
    parts = name.split('.')
    if parts[0] != CORE_LOGGER:
        raise ValueError(f'{name!r} is not a logger of the simulation: its name must start '
                         f'with {CORE_LOGGER!r}')
    for depth in range(1, len(parts) + 1):
        logging.getLogger('.'.join(parts[:depth])).propagate = True
    return logging.getLogger(name)
