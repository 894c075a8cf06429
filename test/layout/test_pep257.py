"""pep257 docstring conventions, as ament_pep257 checks them, over the package."""

import os

from ament_pep257.main import main
import pytest
from repository import ROOT

PATHS = [os.path.join(ROOT, name) for name in ('service_tutorial', 'test', 'launch')]


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257():
    rc = main(argv=PATHS)
    assert rc == 0, 'Found code style errors / warnings'
