"""flake8 with the ament configuration over every Python file of the package."""

import os

from ament_flake8.main import main_with_errors
import pytest
from repository import ROOT

PATHS = [os.path.join(ROOT, name) for name in ('service_tutorial', 'test', 'launch', 'setup.py')]


@pytest.mark.flake8
@pytest.mark.linter
@pytest.mark.long
def test_flake8():
    rc, errors = main_with_errors(argv=PATHS)
    assert rc == 0, f'Found {len(errors)} code style errors / warnings:\n' + '\n'.join(errors)
