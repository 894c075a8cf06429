"""
The robot files GetSpawnables offers, found and read without ROS.

The walk's limits, the source rules, what is left out and why, and the files kept from call to
call.
"""

import math
import os

import pytest
from repository import read_model
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES
from service_tutorial.world_node.standard.spawnable_files import FileWalk, LeftOut, NOT_READ
from service_tutorial.world_node.standard.spawnable_files import RobotFileOffer
from service_tutorial.world_node.standard.spawnable_files import RobotFileReader
from service_tutorial.world_node.standard.spawnable_files import source_folder
from service_tutorial.world_node.standard.spawnable_files import SourceRefused

CRATE = ('<robot name="crate"><link name="body"><inertial><mass value="2"/><inertia ixx="0.05" '
         'iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial><collision><geometry>'
         '<box size="0.4 0.4 0.4"/></geometry></collision></link></robot>')


@pytest.fixture
def share(tmp_path):
    """Make a share folder .../share/pkg with robot files at several depths, and one outside."""
    share = tmp_path / 'share' / 'pkg'
    deep = share / 'urdf' / 'a' / 'b' / 'c' / 'd'
    deep.mkdir(parents=True)
    (share / 'urdf' / 'crate.urdf').write_text(CRATE)
    (share / 'urdf' / 'a' / 'b' / 'c' / 'three.urdf').write_text(CRATE)
    (deep / 'four.urdf').write_text(CRATE)
    (share / 'urdf' / 'notes.txt').write_text('not a robot')
    outside = tmp_path / 'outside'
    outside.mkdir()
    (outside / 'secret.urdf').write_text(CRATE)
    (share / 'urdf' / 'escape.urdf').symlink_to(outside / 'secret.urdf')
    (share / 'urdf' / 'linked').symlink_to(outside)
    (share / 'urdf' / 'alias.urdf').symlink_to(share / 'urdf' / 'crate.urdf')
    return share


def resolver(share):
    return lambda package: str(share) if package == 'pkg' else None


def test_the_walk_keeps_to_its_depth_and_share_and_follows_no_folder_links(share):
    walk = FileWalk()
    walk.walk_package('pkg', os.path.realpath(share))
    assert list(walk.found) == ['package://pkg/urdf/alias.urdf', 'package://pkg/urdf/crate.urdf',
                                'package://pkg/urdf/a/b/c/three.urdf']
    assert walk.found['package://pkg/urdf/alias.urdf'] == os.path.realpath(
        share / 'urdf' / 'crate.urdf')
    assert walk.links_out == ['package://pkg/urdf/escape.urdf']
    assert not walk.cut_short


def test_the_walk_stops_at_its_limits(share):
    walk = FileWalk(max_files=2)
    walk.walk_package('pkg', os.path.realpath(share))
    assert len(walk.found) == 2 and walk.skipped == 1 and walk.cut_short
    # urdf/ holds 6 entries, a/ 1, b/ 1, c/ 2 (d/ is a fourth level down, not looked into).
    for max_entries, cut_short in ((10, False), (9, True), (3, True)):
        walk = FileWalk(max_entries=max_entries)
        walk.walk_package('pkg', os.path.realpath(share))
        assert walk.cut_short == cut_short, max_entries


def test_sources_keep_to_the_installed_shares(share, tmp_path):
    shares = {'pkg': os.path.realpath(share)}
    assert source_folder('package://pkg/urdf/a', shares) == (
        'pkg', shares['pkg'], os.path.join(shares['pkg'], 'urdf', 'a'))
    assert source_folder(f'file://{share}/urdf', shares)[2] == os.path.join(shares['pkg'], 'urdf')
    for source, reason in [
            ('/etc', 'is neither package://<package>/<path> nor file://<absolute path>'),
            ('https://example.com/pkg', 'is neither'),
            ('file:///etc', 'lies outside the share folders of the installed packages'),
            (f'file://{tmp_path}/outside', 'lies outside the share folders'),
            ('file://relative/path', 'is not an absolute path'),
            ('file:///tmp/../etc', "must not contain '..'"),
            ('package://pkg/urdf/../..', "must not contain '..'"),
            ('package://pkg/urdf/linked', 'leads outside the share folder of its package'),
            ('package://pkg/urdf/crate.urdf', 'names no folder'),
            ('package://other/urdf', "package 'other' is not installed"),
            ('package://' + 'p' * 5000, 'is longer than 4096 characters')]:
        with pytest.raises(SourceRefused, match='source .*' + reason.replace('.', r'\.')
                           .replace('(', r'\(').replace(')', r'\)')):
            source_folder(source, shares)


def test_files_are_read_once_and_again_when_they_change(share):
    reader = RobotFileReader(resolver(share), lambda description: [])
    path = os.path.realpath(share / 'urdf' / 'crate.urdf')
    offer = reader.read('package://pkg/urdf/crate.urdf', path)
    assert isinstance(offer, RobotFileOffer)
    assert offer.description == 'crate: no drive or sensors'
    assert [list(corner) for corner in offer.box] == [[-0.2, -0.2, -0.2], [0.2, 0.2, 0.2]]
    # Kept: a deadline long past does not keep it from the answer.
    assert reader.read('package://pkg/urdf/crate.urdf', path, deadline=-math.inf) is offer
    (share / 'urdf' / 'crate.urdf').write_text(CRATE.replace('0.4 0.4 0.4', '0.5 0.5 0.5'))
    assert reader.read('package://pkg/urdf/crate.urdf', path, deadline=-math.inf) is NOT_READ
    again = reader.read('package://pkg/urdf/crate.urdf', path)
    assert [list(corner) for corner in again.box] == [[-0.25, -0.25, -0.25], [0.25, 0.25, 0.25]]


def test_what_is_no_robot_is_left_out_with_the_reason(share):
    reader = RobotFileReader(resolver(share), lambda description: ['a thing'])
    folder = share / 'urdf'
    files = {
        'broken.urdf': ('<robot name="b"><link name=', "broken.urdf' does not parse as XML"),
        'empty.urdf': ('', "empty.urdf' is empty"),
        'entity.urdf': ('<!DOCTYPE r [<!ENTITY e SYSTEM "file:///etc/passwd">]><robot/>',
                        'DOCTYPE or ENTITY declaration'),
        'props.xacro': ('<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
                        '<xacro:property name="p" value="1"/></robot>', 'it has no links'),
        'badmacro.urdf.xacro': ('<robot name="x" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                                '<xacro:nothing/></robot>', 'xacro cannot expand'),
        'latin1.urdf': (None, 'is not UTF-8 text'),
        'sdf.urdf': ('<sdf version="1.9"/>', 'SDF must hold one <model> to spawn'),
        'massless.urdf': ('<robot name="m"><link name="body"><collision><geometry><box '
                          'size="1 1 1"/></geometry></collision></link></robot>',
                          'it does not compile: Error: mass and inertia of moving bodies'),
        'peeking.xml': ('<mujoco><asset><mesh file="/etc/secret.obj"/></asset></mujoco>',
                        "MJCF mesh file '/etc/secret.obj' lies outside"),
        'climbing.mjcf': ('<mujoco><compiler meshdir="../.."/><asset><mesh file="a.obj"/>'
                          '</asset></mujoco>', "MJCF mesh file 'a.obj' lies outside"),
        'linking.xml': ('<mujoco><asset><mesh file="linked/secret.obj"/></asset></mujoco>',
                        "MJCF mesh file 'linked/secret.obj' lies outside"),
    }
    for name, (text, reason) in files.items():
        if text is None:
            (folder / name).write_bytes('<robot name="\xe9"/>'.encode('latin-1'))
        else:
            (folder / name).write_text(text)
        answer = reader.read(f'package://pkg/urdf/{name}', str(folder / name))
        assert isinstance(answer, LeftOut), name
        assert reason in answer.reason, (name, answer.reason)
    (folder / 'package.xml').write_text('<package format="3"/>')
    assert reader.read('package://pkg/urdf/package.xml', str(folder / 'package.xml')) is None
    with open(folder / 'huge.urdf', 'wb') as huge:
        huge.truncate(MAX_MODEL_XML_BYTES + 1)
    assert reader.read('package://pkg/urdf/huge.urdf', str(folder / 'huge.urdf')).reason == \
        "uri 'package://pkg/urdf/huge.urdf' is larger than the limit of 10485760 bytes"


def test_a_robot_says_its_plugins_and_whether_it_is_fixed(share):
    reader = RobotFileReader(resolver(share), lambda description: [
        f'a {setup.kind}' for setup in description.plugins])
    (share / 'urdf' / 'tinybot.urdf').write_text(read_model('tinybot'))
    (share / 'urdf' / 'yard.urdf').write_text(read_model('yard'))
    tinybot = reader.read('package://pkg/urdf/tinybot.urdf', str(share / 'urdf' / 'tinybot.urdf'))
    assert tinybot.description == ('tinybot: a gazebo_ros_diff_drive; a gazebo_ros_ray_sensor; '
                                   'a gazebo_ros_camera; a gazebo_ros_imu_sensor')
    yard = reader.read('package://pkg/urdf/yard.urdf', str(share / 'urdf' / 'yard.urdf'))
    assert yard.description == 'yard: no drive or sensors; fixed to the world'
