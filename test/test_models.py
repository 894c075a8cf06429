"""
Every robot in models/ compiles, settles and runs ten seconds without a MuJoCo warning.

The scenery files there (the yard) are not robots; test_scenery.py loads them.
"""

import glob
import logging
import os

import numpy as np
import pytest
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.world import World

MODELS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'models')
SCENERY_FILES = ('yard.urdf',)
MODEL_FILES = sorted(path for path in glob.glob(os.path.join(MODELS, '*.urdf'))
                     if os.path.basename(path) not in SCENERY_FILES)


def test_the_lesson_models_are_there():
    names = {os.path.basename(path) for path in MODEL_FILES}
    assert {'tinybot.urdf', 'r2d2.urdf'} <= names


@pytest.mark.parametrize('path', MODEL_FILES, ids=os.path.basename)
def test_model_compiles_on_its_own(path):
    with open(path) as urdf_file:
        description = load_urdf(urdf_file.read(), base_dir=MODELS)
    model = description.spec.compile()
    assert model.nbody == len(description.links) + 1
    assert description.root_link == 'base_footprint'


@pytest.mark.parametrize('path', MODEL_FILES, ids=os.path.basename)
def test_model_runs_ten_seconds_without_warnings(path, caplog, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    name = os.path.splitext(os.path.basename(path))[0]
    world = World()
    with caplog.at_level(logging.WARNING, logger='service_tutorial.world'):
        world.spawn_urdf_file(name, path)
        steps = round(10.0 / world.timestep)
        assert world.step(steps) == steps
    assert caplog.text == ''
    assert all(warning.number == 0 for warning in world.data.warning)
    assert np.isfinite(world.data.qpos).all() and np.isfinite(world.data.qvel).all()
    state = world.get_model_state(name)
    # Spawned at the origin with base_footprint on the floor: it stays there, upright, at rest.
    np.testing.assert_allclose(state.position, [0.0, 0.0, 0.0], atol=2e-3)
    np.testing.assert_allclose(np.abs(state.orientation), [1.0, 0.0, 0.0, 0.0], atol=1e-3)
    assert np.linalg.norm(state.linear_velocity) < 1e-3
    assert os.listdir(tmp_path) == []


def test_tinybot_carries_its_diff_drive():
    with open(os.path.join(MODELS, 'tinybot.urdf')) as urdf_file:
        drive = load_urdf(urdf_file.read()).diff_drive
    assert (drive.left_joint, drive.right_joint) == ('wheel_left_joint', 'wheel_right_joint')
    assert drive.wheel_separation == pytest.approx(0.2)
    assert drive.wheel_diameter == pytest.approx(0.066)
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom', 'base_footprint')
