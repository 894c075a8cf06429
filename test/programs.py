"""The package's installed programs, found and run as `ros2 run service_tutorial ...` runs them."""

import os
import subprocess
import threading

from ament_index_python.packages import get_package_prefix

PACKAGE = 'service_tutorial'


def program_path(name):
    """Return the path of an installed program of the package: <prefix>/lib/service_tutorial."""
    return os.path.join(get_package_prefix(PACKAGE), 'lib', PACKAGE, name)


def run_program(name, *args, stdin=None, timeout=60):
    """Run an installed program to its end, with stdin typed in if given; return the process."""
    return subprocess.run([program_path(name), *args], input=stdin, capture_output=True,
                          text=True, timeout=timeout)


def lines_of(process, *, timeout=60):
    """
    Yield the lines a started program prints, as they come.

    A net for a hang, not a time limit: timeout s after the reading starts, a program whose
    lines have not ended (or been left) is killed, which ends them, so that the test fails on
    what it then reads instead of waiting for ever.
    """
    watchdog = threading.Timer(timeout, process.kill)
    watchdog.start()
    try:
        for line in process.stdout:  # not yield from: closing this must leave stdout open
            yield line
    finally:
        watchdog.cancel()
