"""Pose composition and reference frames, against cases worked out by hand."""

import math

import mujoco
import numpy as np
import pytest
from service_tutorial.sim import frames
from service_tutorial.sim.frames import ModelState
from service_tutorial.sim.validation import WorldError

HALF = math.sqrt(0.5)
YAW_90 = (HALF, 0.0, 0.0, HALF)


def state(position, orientation=(1.0, 0.0, 0.0, 0.0), linear=(0.0, 0.0, 0.0),
          angular=(0.0, 0.0, 0.0)):
    return ModelState(np.array(position, float), np.array(orientation, float),
                      np.array(linear, float), np.array(angular, float))


@pytest.mark.parametrize('yaw, expected', [
    (0.0, (1.0, 0.0, 0.0, 0.0)),
    (math.pi / 2.0, YAW_90),
    (-math.pi / 2.0, (HALF, 0.0, 0.0, -HALF)),
    (math.pi, (0.0, 0.0, 0.0, 1.0)),
])
def test_yaw_quaternion_is_a_turn_about_z(yaw, expected):
    np.testing.assert_allclose(frames.yaw_quaternion(yaw), expected, atol=1e-15)


def test_rotation_of_a_vector_by_a_quarter_turn():
    # Yawed 90 degrees, a frame's x axis points along the world's y axis.
    np.testing.assert_allclose(frames.rotate(YAW_90, (1.0, 0.0, 0.0)), [0.0, 1.0, 0.0],
                               atol=1e-15)
    np.testing.assert_allclose(frames.rotate_back(YAW_90, (0.0, 1.0, 0.0)), [1.0, 0.0, 0.0],
                               atol=1e-15)


def test_pose_in_a_turned_frame_composes_to_the_hand_worked_world_pose():
    # A frame at (1, 2, 0) facing +y; one metre ahead of it and turned a further quarter turn
    # is (1, 3, 0) in the world, facing -x.
    position, orientation = frames.compose((1.0, 2.0, 0.0), YAW_90, (1.0, 0.0, 0.0), YAW_90)
    np.testing.assert_allclose(position, [1.0, 3.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(orientation, [0.0, 0.0, 0.0, 1.0], atol=1e-15)
    back_position, back_orientation = frames.relative((1.0, 2.0, 0.0), YAW_90, position,
                                                      orientation)
    np.testing.assert_allclose(back_position, [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(back_orientation, YAW_90, atol=1e-15)


def test_twist_seen_from_a_moving_turned_frame():
    frame = state((0.0, 0.0, 0.0), YAW_90, linear=(0.0, 1.0, 0.0), angular=(0.0, 0.0, 0.5))
    body = state((0.0, 2.0, 0.0), linear=(1.0, 1.0, 0.0), angular=(0.0, 0.0, 1.5))
    seen = frames.expressed_in(frame, body)
    # 2 m along the world's y is 2 m along the frame's x; the relative velocity (1, 0, 0) in
    # the world points along the frame's -y.
    np.testing.assert_allclose(seen.position, [2.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(seen.orientation, [HALF, 0.0, 0.0, -HALF], atol=1e-15)
    np.testing.assert_allclose(seen.linear_velocity, [0.0, -1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(seen.angular_velocity, [0.0, 0.0, 1.0], atol=1e-15)
    again = frames.in_world(frame, seen)
    for field in ('position', 'orientation', 'linear_velocity', 'angular_velocity'):
        np.testing.assert_allclose(getattr(again, field), getattr(body, field), atol=1e-15)


class Spawned:
    """Stands in for a spawned model: all frames.frame_body reads of one is its root body."""

    def __init__(self, root_id):
        self.root_id = root_id


def test_frame_names_resolve_to_bodies():
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name='bot::base').add_body(name='bot::arm').add_geom(size=[0.1, 0, 0])
    mj_model = spec.compile()
    models = {'bot': Spawned(1)}
    assert frames.frame_body('', models, mj_model) == 0
    assert frames.frame_body('world', models, mj_model) == 0
    assert frames.frame_body('bot', models, mj_model) == 1
    assert frames.frame_body('bot::arm', models, mj_model) == 2
    for name, shown in [('bot::', "'bot::'"), ('bot::leg', "'bot::leg'"),
                        ('other::arm', "'other::arm'"), ('x' * 90, f"'{'x' * 80}...'"),
                        (3, '3')]:
        with pytest.raises(WorldError) as refused:
            frames.frame_body(name, models, mj_model)
        assert str(refused.value).startswith(f'unknown reference frame {shown}')
