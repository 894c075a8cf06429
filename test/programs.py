"""The package's installed programs, found and run as `ros2 run service_tutorial ...` runs them."""

import os
import subprocess

from ament_index_python.packages import get_package_prefix

PACKAGE = 'service_tutorial'


def program_path(name):
    """Return the path of an installed program of the package: <prefix>/lib/service_tutorial."""
    return os.path.join(get_package_prefix(PACKAGE), 'lib', PACKAGE, name)


def run_program(name, *args, stdin=None, timeout=60):
    """Run an installed program to its end, with stdin typed in if given; return the process."""
    return subprocess.run([program_path(name), *args], input=stdin, capture_output=True,
                          text=True, timeout=timeout)
