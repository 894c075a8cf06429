"""Robot files as people have them: URDF as it is, xacro expanded by the real xacro package."""

import os

from lxml import etree
import pytest
from repository import MODELS, R2D2, TEST_MODELS, TINYBOT
from service_tutorial.sim.robot_files import file_model_name, parse_xacro_arguments
from service_tutorial.sim.robot_files import read_path
from service_tutorial.sim.validation import WorldError

MAST = os.path.join(TEST_MODELS, 'ros_mast_tinybot.urdf.xacro')
UNKNOWN_PACKAGE = os.path.join(TEST_MODELS, 'ros_unknown_package.urdf.xacro')


def parsed(robot_file):
    return etree.fromstring(robot_file.text.encode())


def mast_size(robot_file):
    return parsed(robot_file).find("link[@name='mast_link']/visual/geometry/box").get('size')


def test_a_plain_urdf_comes_back_as_written_with_its_folder():
    path = TINYBOT
    robot_file = read_path(path)
    with open(path) as urdf_file:
        assert robot_file.text == urdf_file.read()
    assert robot_file.base_dir == MODELS


def test_xacro_finds_the_package_through_the_ament_index_and_takes_arguments():
    default = read_path(MAST)
    tall = read_path(MAST, xacro_arguments={'mast_height': '0.5'})

    links = {link.get('name') for link in parsed(default).findall('link')}
    # tinybot.urdf came from the installed package's share, through $(find service_tutorial).
    assert {'base_footprint', 'base_link', 'wheel_left_link', 'mast_link'} <= links
    assert parsed(default).get('name') == 'mast_tinybot'
    assert parsed(default).find('gazebo/plugin').get('filename') == 'libgazebo_ros_diff_drive.so'
    assert mast_size(default) == '0.01 0.01 0.2'
    assert mast_size(tall) == '0.01 0.01 0.5'
    assert tall.base_dir == TEST_MODELS
    assert 'xacro' not in parsed(tall).nsmap


def test_xacro_is_recognised_by_its_namespace_whatever_the_file_is_called():
    robot_file = read_path(os.path.join(TEST_MODELS, 'ros_gripper_parts.xml'))
    fingers = parsed(robot_file).findall('link')
    assert [link.get('name') for link in fingers] == ['palm', 'left_finger', 'right_finger']


def test_the_arguments_handed_in_are_left_as_they_were():
    # xacro writes every argument's default into the mapping it is given.
    arguments = {'mast_height': '0.3'}
    assert mast_size(read_path(MAST, xacro_arguments=arguments)) == '0.01 0.01 0.3'
    assert arguments == {'mast_height': '0.3'}
    assert mast_size(read_path(MAST)) == '0.01 0.01 0.2'


def test_a_file_suggests_its_model_name_without_urdf_and_xacro_extensions():
    assert file_model_name('/a/tinybot.urdf') == 'tinybot'
    assert file_model_name('robot.urdf.xacro') == 'robot'
    assert file_model_name('tinybot_diff.xacro') == 'tinybot_diff'
    assert file_model_name('arm.sdf') == 'arm'
    assert file_model_name('arm.usd') == 'arm.usd'


def test_arguments_are_name_colon_equals_value():
    assert parse_xacro_arguments(['a:=1', 'b:=x:=y', 'c:=']) == {'a': '1', 'b': 'x:=y', 'c': ''}
    assert parse_xacro_arguments(None) == {}
    for text in ('mast_height', ':=1', 'a=1'):
        with pytest.raises(WorldError, match=f"xacro argument '{text}' for 'f.xacro' is "
                           'not name:=value'):
            parse_xacro_arguments([text], path='f.xacro')


@pytest.mark.parametrize('path, arguments, reason', [
    (UNKNOWN_PACKAGE, None, "package 'no_such_package_xyz' not found"),
    (MAST, {'mast_height': 'tall'}, "when evaluating expression 'mast_height / 2'"),
])
def test_a_xacro_failure_is_one_line_naming_the_file(path, arguments, reason):
    with pytest.raises(WorldError) as failure:
        read_path(path, xacro_arguments=arguments)
    message = str(failure.value)
    assert message.startswith(f"xacro cannot expand '{path}': ")
    assert reason in message
    assert '\n' not in message


def test_broken_xml_in_a_xacro_file_is_one_line_naming_the_file(tmp_path):
    path = tmp_path / 'broken.urdf.xacro'
    path.write_text('<robot name="b" xmlns:xacro="http://www.ros.org/wiki/xacro">\n'
                    '<link name="a">\n</robot>\n')
    with pytest.raises(WorldError, match=f"^xacro cannot expand '{path}': mismatched tag: "
                       r'line 3, column 2$'):
        read_path(str(path))


def test_unreadable_files_and_misplaced_arguments_are_refused_naming_the_file(tmp_path):
    missing = str(tmp_path / 'missing.urdf.xacro')
    with pytest.raises(WorldError, match=f"^robot file '{missing}' cannot be read: No such "
                                         'file or directory$'):
        read_path(missing)
    binary = tmp_path / 'binary.urdf'
    binary.write_bytes(b'\xff\xfe<\x00r\x00')
    with pytest.raises(WorldError, match=f"^robot file '{binary}' is not UTF-8 text$"):
        read_path(str(binary))
    plain = R2D2
    with pytest.raises(WorldError, match='which is not a xacro file'):
        read_path(plain, xacro_arguments={'mast_height': '1'})
