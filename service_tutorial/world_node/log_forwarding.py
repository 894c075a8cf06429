"""
What the simulation logs through Python's logging, passed on to a node's rclpy logger.

The core (service_tutorial.sim) knows nothing of ROS and logs to the `service_tutorial` loggers:
spawns, deletes, recoveries, MuJoCo's warnings. forward_core_logs(node) hangs a handler on that
logger which hands each record to the node's logger, so that the console of `ros2 run` and
/rosout show it under the node's name; the handle it returns takes the handler off again.

The records still propagate to the root logger as usual, whatever logger class `launch` or
anything else installed (sim/core_logs.py): an application that configured logging for itself
(or pytest's caplog) sees them too, and a plain `ros2 run` has no root handler, so nothing is
printed twice. The `service_tutorial` logger is given the node logger's level while forwarding,
since Python's default level (WARNING) would drop spawns and deletes.
"""

import logging
import sys

from rclpy.impl.implementation_singleton import rclpy_implementation
from rclpy.logging import LoggingSeverity
from service_tutorial.sim.core_logs import CORE_LOGGER, core_logger

# rclpy's severities are Python's levels; a record goes out at the highest one it reaches.
_SEVERITIES = (LoggingSeverity.FATAL, LoggingSeverity.ERROR, LoggingSeverity.WARN,
               LoggingSeverity.INFO, LoggingSeverity.DEBUG)


class RclpyHandler(logging.Handler):
    """A logging.Handler that writes each record to an rclpy logger at the same severity."""

    def __init__(self, ros_logger):
        super().__init__()
        self.ros_logger = ros_logger

    def emit(self, record):
        """
        Pass a record on, with the place in the core that logged it.

        The record knows where it was logged; the rclpy logger's own methods would look for
        their caller with inspect, reading source files, about 0.4 ms a message, which was a
        fifth of a spawn through the service.
        """
        try:
            message = self.format(record)
            severity = next((severity for severity in _SEVERITIES
                             if record.levelno >= severity), LoggingSeverity.DEBUG)
            _write(self.ros_logger, severity, message, record.funcName, record.pathname,
                   record.lineno)
        except Exception:  # a failing log call must not fail the step that logged
            self.handleError(record)


def log_here(ros_logger, severity, message):
    """
    Log message on an rclpy logger, naming the caller's place as its own methods would.

    Those find their caller with inspect, whose first use in a process walks every module
    loaded: 70 ms of the world's start-up, with yourdfpy's imports loaded, for its first line.
    """
    caller = sys._getframe(1)
    _write(ros_logger, severity, message, caller.f_code.co_name, caller.f_code.co_filename,
           caller.f_lineno)


def _write(ros_logger, severity, message, function, path, line):
    if ros_logger.is_enabled_for(severity):
        rclpy_implementation.rclpy_logging_rcutils_log(
            severity, ros_logger.name, message, function, path, line)


class ForwardedLogs:
    """The handler forward_core_logs() installed, and the level it replaced."""

    def __init__(self, handler, logger, previous_level):
        self.handler = handler
        self.logger = logger
        self.previous_level = previous_level

    def stop(self):
        """Take the handler off and give the logger its level back."""
        if self.handler is None:
            return
        self.logger.removeHandler(self.handler)
        self.logger.setLevel(self.previous_level)
        self.handler = None


def forward_core_logs(node):
    """Send the `service_tutorial` loggers' records to node's logger until stop() is called."""
    ros_logger = node.get_logger()
    logger = core_logger(CORE_LOGGER)
    previous_level = logger.level
    # rclpy's severities are Python's levels: DEBUG 10, INFO 20, WARN 30, ERROR 40, FATAL 50.
    logger.setLevel(int(ros_logger.get_effective_level()) or logging.INFO)
    handler = RclpyHandler(ros_logger)
    logger.addHandler(handler)
    return ForwardedLogs(handler, logger, previous_level)
