"""Where the repository's files are, for every layer of tests: its root and its robot models."""

import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The package's robots and scenery, installed to share/service_tutorial/models.
MODELS = os.path.join(ROOT, 'models')
# Robots and props written for the tests, never installed.
TEST_MODELS = os.path.join(ROOT, 'test', 'models')
# The lesson's own robot files, beside the repository where they are there (never copied).
LESSON_ROBOTS = os.path.join(os.path.dirname(ROOT), 'shared', 'lesson', 'robots')
# The lesson's two robots.
TINYBOT = os.path.join(MODELS, 'tinybot.urdf')
R2D2 = os.path.join(MODELS, 'r2d2.urdf')
# MJCF entities written for the tests: a free crate, and an arm with a hinge and its actuator.
MJCF_CRATE = os.path.join(TEST_MODELS, 'mjcf', 'crate.xml')
MJCF_ARM = os.path.join(TEST_MODELS, 'mjcf', 'arm.xml')


def read_file(path):
    """Return the text of a file."""
    with open(path, encoding='utf-8') as text_file:
        return text_file.read()


def model_path(name, folder=MODELS):
    """Return the path of a model, named without .urdf, in models/ or another folder."""
    return os.path.join(folder, name + '.urdf')


def read_model(name, folder=MODELS):
    """Return the URDF of a model, named without .urdf, in models/ or another folder."""
    return read_file(model_path(name, folder))


def install_package(tmp_path, monkeypatch, name):
    """Install an empty ament package under tmp_path, found first; return its share folder."""
    prefix = tmp_path / 'prefix'
    index = prefix / 'share' / 'ament_index' / 'resource_index' / 'packages'
    index.mkdir(parents=True, exist_ok=True)
    (index / name).write_text('')
    share = prefix / 'share' / name
    share.mkdir(parents=True, exist_ok=True)
    monkeypatch.setenv('AMENT_PREFIX_PATH',
                       f'{prefix}{os.pathsep}{os.environ.get("AMENT_PREFIX_PATH", "")}')
    return share
