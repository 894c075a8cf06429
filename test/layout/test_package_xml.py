"""package.xml names every package the code imports, under its rosdep key where one exists."""

import ast
import glob
import os
import sys
import xml.etree.ElementTree as ElementTree

from repository import ROOT

# Python modules whose rosdep key is not their own name; ROS packages are keys themselves.
ROSDEP_KEYS = {
    'PIL': 'python3-pil', 'hypothesis': 'python3-hypothesis', 'lxml': 'python3-lxml',
    'numpy': 'python3-numpy', 'pytest': 'python3-pytest', 'yaml': 'python3-yaml',
}
# pip-installed, as package.xml says; websockets and msgspec come with viser (the tests open the
# page's websocket as viser's browser client does).
WITHOUT_KEY = ('mujoco', 'yourdfpy', 'trimesh', 'viser', 'selenium', 'websockets', 'msgspec')
# This package, and the modules the tests import from the repository's folders.
OWN_MODULES = {'service_tutorial'} | {
    os.path.splitext(os.path.basename(path))[0]
    for folder in ('test', 'benchmarks', 'stress')
    for path in glob.glob(f'{ROOT}/{folder}/**/*.py', recursive=True)}


def imported_modules(pattern):
    """Return the top-level modules imported by the Python files that match a glob pattern."""
    modules = set()
    for path in glob.glob(os.path.join(ROOT, pattern), recursive=True):
        with open(path) as source:
            tree = ast.parse(source.read(), path)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                modules.update(alias.name.split('.')[0] for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                modules.add(node.module.split('.')[0])
    return modules - set(sys.stdlib_module_names) - OWN_MODULES


def declared(*kinds):
    """Return the dependencies of these kinds (exec_depend, test_depend, ...) in package.xml."""
    tree = ElementTree.parse(os.path.join(ROOT, 'package.xml'))
    return {element.text for kind in kinds for element in tree.getroot().iter(kind)}


def test_what_the_package_and_its_launch_file_import_is_an_exec_depend():
    needed = imported_modules('service_tutorial/**/*.py') | imported_modules('launch/*.py')
    keys = {ROSDEP_KEYS.get(module, module) for module in needed - set(WITHOUT_KEY)}
    assert keys - declared('exec_depend', 'depend') == set()


def test_what_the_tests_import_is_a_test_or_exec_depend():
    needed = imported_modules('test/**/*.py')
    keys = {ROSDEP_KEYS.get(module, module) for module in needed - set(WITHOUT_KEY)}
    assert keys - declared('exec_depend', 'depend', 'test_depend') == set()


def test_packages_without_a_rosdep_key_are_named_in_a_comment():
    with open(os.path.join(ROOT, 'package.xml')) as package_xml:
        comments = [line for line in package_xml if '<!--' in line]
    for module in WITHOUT_KEY:
        assert any(module in comment for comment in comments), module
