"""
One way in: one module opens robot files, one lists the installed packages.

Every file the package opens is opened by a module that says here what it opens; robot files
(URDF, xacro, MJCF, SDF) only by the reader, sim/robot_files.py, and nothing hands a path to
xacro or MuJoCo to open for it elsewhere. The installed packages are listed by
world_node/packages.py alone. Each rule has a self-test that shows it catches a module that
breaks it.
"""

import ast
import os

from repository import ROOT

PACKAGE = os.path.join(ROOT, 'service_tutorial')
# Every module that opens files, and what it opens.
OPENERS = {
    'sim/robot_files.py': 'robot files: URDF, xacro, MJCF, SDF and model.config',
    'sim/world_files.py': 'world files',
    'sim/urdf/meshes.py': 'the mesh files a robot names',
    'sim/background_renders.py': 'the names of its threads, in /proc',
    'world_node/bridge_config.py': "ros_gz_bridge's YAML configuration files",
    'testing/isolation.py': 'the lock file of a ROS domain',
    'pictures/turning_demo.py': "the demo's logs",
    'pictures/trajectory_plot.py': 'the SVG picture it writes',
    'lesson/robot_turning_action_client.py': 'the null device',
}
ROBOT_READER = 'sim/robot_files.py'
# Calls that open a robot file for the caller.
ROBOT_FILE_OPENERS = ('process_file', 'from_file', 'from_xml_path')
OPEN_CALLS = ('open', 'io.open', 'os.open')
PATH_OPEN_METHODS = ('read_text', 'read_bytes', 'write_text', 'write_bytes')
PACKAGE_LISTERS = ('get_packages_with_prefixes', 'get_resources', 'get_search_paths')
PACKAGE_LIST = 'world_node/packages.py'


def modules():
    """Return {path relative to the package: parsed module} of every module of the package."""
    found = {}
    for directory, _, names in os.walk(PACKAGE):
        for name in names:
            if name.endswith('.py'):
                path = os.path.join(directory, name)
                with open(path, encoding='utf-8') as source:
                    found[os.path.relpath(path, PACKAGE)] = ast.parse(source.read())
    return found


def called(tree, names, methods=()):
    """
    Return the lines that call a function whose dotted name is or ends with one of names.

    methods: names that count only when called on an object (path.read_text()).
    """
    lines = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            function = ast.unparse(node.func)
            if (any(function == name or function.endswith('.' + name) for name in names)
                    or isinstance(node.func, ast.Attribute) and node.func.attr in methods):
                lines.append(node.lineno)
    return sorted(lines)


def opens_files(tree):
    """Return the lines of a module that open a file."""
    return called(tree, OPEN_CALLS, PATH_OPEN_METHODS)


def test_the_walk_finds_every_way_of_opening_a_file():
    tree = ast.parse('import io\nwith open(p) as f:\n    pass\nio.open(p)\n'
                     'pathlib.Path(p).read_text()\nxacro.process_file(p)\n'
                     'mujoco.MjSpec.from_file(p)\nx.open_door()\nread_text(t)\n')
    assert opens_files(tree) == [2, 4, 5]
    assert called(tree, ROBOT_FILE_OPENERS) == [6, 7]
    assert called(ast.parse('from ament_index_python import packages\n'
                            'packages.get_packages_with_prefixes()\n'),
                  PACKAGE_LISTERS) == [2]


def test_only_the_modules_that_say_what_they_open_open_files():
    opening = {path for path, tree in modules().items() if opens_files(tree)}
    assert opening <= set(OPENERS), f'modules that open files: {sorted(opening - set(OPENERS))}'
    assert [path for path, what in OPENERS.items() if 'robot files' in what] == [ROBOT_READER]


def test_robot_files_are_opened_by_the_reader_alone():
    others = {path: lines for path, tree in modules().items()
              if path != ROBOT_READER and (lines := called(tree, ROBOT_FILE_OPENERS))}
    assert not others, f'robot files opened outside {ROBOT_READER}: {others}'


def test_the_installed_packages_are_listed_in_one_place():
    listing = {path for path, tree in modules().items() if called(tree, PACKAGE_LISTERS)}
    assert listing == {PACKAGE_LIST}
