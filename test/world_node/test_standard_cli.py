"""
The README's `ros2 service call` of the standard interfaces prints what the README shows.

Run where Jazzy's `ros2` command is (the CI's Jazzy leg; the wheels have none), against the
world of the test harness on the test's own ROS domain, with the standard's types from whichever
simulation_interfaces is installed (the real package on Jazzy).
"""

import importlib.metadata
import os
import re
import shutil
import subprocess

import pytest
from repository import read_file, ROOT

pytestmark = pytest.mark.ros
FEATURES_CALL = ('ros2 service call /get_simulator_features '
                 'simulation_interfaces/srv/GetSimulatorFeatures')


def readme_answer(call):
    """Return the output block the README shows right after the block of a command."""
    readme = read_file(os.path.join(ROOT, 'README.md'))
    after_call = readme.split(call + '\n```\n', 1)
    assert len(after_call) == 2, f'the README shows no block with {call!r}'
    shown = re.match(r'\n```text\n(.*?)```\n', after_call[1], re.DOTALL)
    assert shown, f'the README shows no output after {call!r}'
    return shown.group(1)


def test_get_simulator_features_prints_what_the_readme_shows(fast_world):
    if shutil.which('ros2') is None:
        pytest.skip('the ros2 command is not installed (the PyPI wheels have none)')
    printed = subprocess.run(FEATURES_CALL.split(), capture_output=True, text=True,
                             timeout=60, check=True).stdout
    # The README was printed with one MuJoCo; the world says which one it runs.
    shown = re.sub(r'MuJoCo \S+ world',
                   f'MuJoCo {importlib.metadata.version("mujoco")} world',
                   readme_answer(FEATURES_CALL))
    printed = printed.replace('waiting for service to become available...\n', '')
    assert printed.rstrip() == shown.rstrip()
