"""
Every robot in models/ and test/models/ compiles, settles and runs 10 s without warnings.

The scenery in models/ (the yard) and the props of test/models/props/ are not robots; the
tests of scenery and sensors load them.
"""

import glob
import logging
import os

import numpy as np
import pytest
from repository import MODELS, TEST_MODELS, TINYBOT
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file

SCENERY_FILES = ('yard.urdf',)
LESSON_FILES = sorted(path for path in glob.glob(os.path.join(MODELS, '*.urdf'))
                      if os.path.basename(path) not in SCENERY_FILES)
MODEL_FILES = LESSON_FILES + sorted(glob.glob(os.path.join(TEST_MODELS, '*.urdf')))


def test_the_lesson_models_are_there():
    names = {os.path.basename(path) for path in LESSON_FILES}
    assert {'tinybot.urdf', 'r2d2.urdf'} <= names


def test_the_test_models_cover_every_drive_and_mesh_format():
    names = {os.path.basename(path) for path in MODEL_FILES} - {
        os.path.basename(path) for path in LESSON_FILES}
    assert {'diffbot_ros1.urdf', 'diffbot_ros2.urdf', 'pairbot_ros2.urdf', 'skidbot_ros1.urdf',
            'meshbot.urdf', 'missingbot.urdf', 'linkbot.urdf'} <= names


@pytest.mark.parametrize('path', MODEL_FILES, ids=os.path.basename)
def test_model_compiles_on_its_own(path):
    with open(path) as urdf_file:
        description = load_urdf(urdf_file.read(), base_dir=os.path.dirname(path))
    model = description.spec.compile()
    assert model.nbody == len(description.links) + 1
    assert description.root_link == 'base_footprint'


@pytest.mark.parametrize('path', MODEL_FILES, ids=os.path.basename)
def test_model_runs_ten_seconds_without_warnings(path, caplog, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    name = os.path.splitext(os.path.basename(path))[0]
    world = World()
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        model = spawn_file(world, name, path)
        steps = round(10.0 / world.timestep)
        assert world.step(steps) == steps
    # The lesson's robots spawn without a word; a test robot only with its notes (meshes
    # left out, plugins ignored), never with a MuJoCo warning.
    notes = [f"model '{name}': {note}" for note in model.description.notes]
    assert [record.getMessage() for record in caplog.records] == notes
    if path in LESSON_FILES:
        assert notes == []
    assert all(warning.number == 0 for warning in world.data.warning)
    assert np.isfinite(world.data.qpos).all() and np.isfinite(world.data.qvel).all()
    state = world.get_model_state(name)
    # Spawned at the origin with base_footprint on the floor: it stays there, upright, at rest.
    np.testing.assert_allclose(state.position, [0.0, 0.0, 0.0], atol=2e-3)
    np.testing.assert_allclose(np.abs(state.orientation), [1.0, 0.0, 0.0, 0.0], atol=1e-3)
    assert np.linalg.norm(state.linear_velocity) < 1e-3
    assert os.listdir(tmp_path) == []


def test_tinybot_carries_its_diff_drive():
    with open(TINYBOT) as urdf_file:
        drive = load_urdf(urdf_file.read()).diff_drive
    assert (drive.left_joint, drive.right_joint) == ('wheel_left_joint', 'wheel_right_joint')
    assert drive.wheel_separation == pytest.approx(0.2)
    assert drive.wheel_diameter == pytest.approx(0.066)
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom', 'base_footprint')
