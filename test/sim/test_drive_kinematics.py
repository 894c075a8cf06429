"""Differential-drive maths: wheel speeds, body velocity and odometry integration."""

import math

import pytest
from service_tutorial.sim.plugins.diff_drive import body_velocity
from service_tutorial.sim.plugins.diff_drive import EncoderOdometry
from service_tutorial.sim.plugins.diff_drive import integrate_arc
from service_tutorial.sim.plugins.diff_drive import wheel_speeds
from service_tutorial.sim.plugins.drive_config import DiffDriveConfig

SEPARATION = 0.2
RADIUS = 0.033


def test_straight_drive_turns_both_wheels_alike():
    left, right = wheel_speeds(0.2, 0.0, SEPARATION, RADIUS)
    assert left == pytest.approx(0.2 / RADIUS)
    assert right == pytest.approx(0.2 / RADIUS)


def test_turning_in_place_turns_wheels_opposite():
    left, right = wheel_speeds(0.0, 1.0, SEPARATION, RADIUS)
    # Positive angular_z turns left (REP 103): the right wheel runs forward.
    assert right == pytest.approx(SEPARATION / 2.0 / RADIUS)
    assert left == pytest.approx(-right)


def test_arc_wheel_speeds_follow_the_rim_speeds():
    left, right = wheel_speeds(0.3, 0.5, SEPARATION, RADIUS)
    assert left * RADIUS == pytest.approx(0.3 - 0.5 * SEPARATION / 2.0)
    assert right * RADIUS == pytest.approx(0.3 + 0.5 * SEPARATION / 2.0)


@pytest.mark.parametrize('linear_x, angular_z', [(0.2, 0.0), (0.0, -1.5), (0.25, 0.7)])
def test_body_velocity_inverts_wheel_speeds(linear_x, angular_z):
    left, right = wheel_speeds(linear_x, angular_z, SEPARATION, RADIUS)
    assert body_velocity(left, right, SEPARATION, RADIUS) == pytest.approx(
        (linear_x, angular_z))


def test_quarter_circle_arc_ends_where_geometry_says():
    x, y, yaw = integrate_arc(0.0, 0.0, 0.0, math.pi / 2.0, math.pi / 2.0)
    assert (x, y, yaw) == pytest.approx((1.0, 1.0, math.pi / 2.0))


def test_arc_from_a_rotated_start():
    # Heading +y, turning right by a quarter circle of radius 2.
    x, y, yaw = integrate_arc(1.0, 1.0, math.pi / 2.0, math.pi, -math.pi / 2.0)
    assert (x, y, yaw) == pytest.approx((3.0, 3.0, 0.0))


def test_straight_line_without_turn():
    assert integrate_arc(1.0, 2.0, math.pi / 4.0, math.sqrt(2.0), 0.0) == pytest.approx(
        (2.0, 3.0, math.pi / 4.0))


def test_encoder_odometry_of_a_known_arc_does_not_depend_on_update_rate():
    # Left rim travels 0.9 m, right rim 1.1 m: a 1 m arc turning 1 rad (radius 1 m).
    left_angle, right_angle = 0.9 / RADIUS, 1.1 / RADIUS
    coarse = EncoderOdometry(SEPARATION, RADIUS)
    coarse.update(left_angle, right_angle)
    fine = EncoderOdometry(SEPARATION, RADIUS)
    for step in range(1, 101):
        fine.update(left_angle * step / 100.0, right_angle * step / 100.0)
    expected = (math.sin(1.0), 1.0 - math.cos(1.0), 1.0)
    assert (coarse.x, coarse.y, coarse.yaw) == pytest.approx(expected, abs=1e-12)
    assert (fine.x, fine.y, fine.yaw) == pytest.approx(expected, abs=1e-12)


def test_encoder_odometry_reset_starts_from_current_angles():
    odometry = EncoderOdometry(SEPARATION, RADIUS)
    odometry.update(10.0, 10.0)
    odometry.reset(10.0, 12.0)
    assert (odometry.x, odometry.y, odometry.yaw) == (0.0, 0.0, 0.0)
    odometry.update(11.0, 13.0)
    assert odometry.x == pytest.approx(RADIUS)
    assert odometry.yaw == pytest.approx(0.0)


def test_config_exposes_radius_and_first_wheel_pair():
    config = DiffDriveConfig(left_joints=('l1', 'l2'), right_joints=('r1', 'r2'),
                             wheel_diameter=0.1)
    assert config.wheel_radius == pytest.approx(0.05)
    assert (config.left_joint, config.right_joint) == ('l1', 'r1')
    assert (config.odometry_frame, config.robot_base_frame) == ('odom', 'base_footprint')
