"""
Scenery: static obstacles from a file, part of the world's scene rather than a model.

A URDF whose root link is fixed to the link `world` (the builder's anchored robot), with fixed
joints only and no plugins, or an MJCF file without joints, without <include> and without files
outside its own folder (a scenery given as text names no file at all). Its bodies
are welded to the world, so they collide and are seen by lasers and cameras, but they are not
a model: get_model_list does not name them, and no service moves or deletes them.
"""

import os

from lxml import etree
import mujoco
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.urdf.hardened_xml import MAX_MODEL_XML_BYTES
from service_tutorial.sim.urdf.hardened_xml import parse_xml
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import WorldError

# Names of the scenery's elements in the world's model; no model name holds a '/'.
SCENERY_PREFIX = 'scenery/'


class SceneryError(WorldError):
    """A scenery the world refuses; unsupported: it holds what scenery may not (joints...)."""

    def __init__(self, message, *, unsupported=False):
        super().__init__(message)
        self.unsupported = unsupported


class Scenery:
    """The static obstacles of one file, ready to be added to every spec the world builds."""

    def __init__(self, path, *, package_resolver=None):
        """Read and check a URDF or MJCF file of static obstacles, or raise SceneryError."""
        self.path = os.path.abspath(path)
        try:
            with open(self.path, 'rb') as scenery_file:
                text = scenery_file.read(MAX_MODEL_XML_BYTES + 1)
        except OSError as error:
            raise SceneryError(f'cannot read scenery file {quoted(path)}: {error.strerror}') \
                from None
        self._load(text, f'scenery file {quoted(path)}', os.path.dirname(self.path),
                   package_resolver)

    @classmethod
    def from_text(cls, text, what, *, package_resolver=None):
        """Return the Scenery of a URDF or MJCF text that names no file, or raise SceneryError."""
        scenery = cls.__new__(cls)
        scenery.path = None
        scenery._load(text.encode('utf-8') if isinstance(text, str) else bytes(text), what,
                      None, package_resolver)
        return scenery

    def _load(self, text, what, base_dir, package_resolver):
        if len(text) > MAX_MODEL_XML_BYTES:
            raise SceneryError(f'{what} is larger than {MAX_MODEL_XML_BYTES} bytes')
        try:
            root = parse_xml(text, what)
        except UrdfError as error:
            raise SceneryError(str(error)) from None
        tag = etree.QName(root).localname if isinstance(root.tag, str) else ''
        if tag == 'robot':
            self._spec, self._position, self._orientation = self._from_urdf(
                text, what, base_dir, package_resolver)
        elif tag == 'mujoco':
            self._spec, self._position, self._orientation = self._from_mjcf(
                root, text, what, base_dir)
        else:
            raise SceneryError(f'{what} is neither URDF nor MJCF: its root element is '
                               f'<{tag[:40]}>')
        try:
            probe = mujoco.MjSpec()
            self.attach(probe)
            probe.compile()
        except Exception as error:
            reason = ' '.join(str(error).split()).removeprefix('Error: ')
            raise SceneryError(f'{what} does not compile: {reason}') from None

    def _from_urdf(self, text, what, base_dir, package_resolver):
        try:
            description = load_urdf(text, base_dir=base_dir, package_resolver=package_resolver)
        except UrdfError as error:
            raise SceneryError(f'{what}: {error}') from None
        if not description.anchored:
            raise SceneryError(f'{what} must fix its root link {quoted(description.root_link)} '
                               "to the link 'world' with a fixed joint", unsupported=True)
        if description.joints:
            raise SceneryError(f'{what} has moving joints ({", ".join(description.joints)}); '
                               'scenery is static', unsupported=True)
        if description.plugins:
            raise SceneryError(f'{what} carries plugins; scenery is static', unsupported=True)
        return (description.spec, description.root_position, description.root_orientation)

    def _from_mjcf(self, root, text, what, base_dir):
        if next(root.iter('include'), None) is not None:
            raise SceneryError(f'{what} has an <include>, which scenery files may not have',
                               unsupported=True)
        for element in root.iter():
            for attribute in ('file', 'meshdir', 'texturedir', 'assetdir'):
                name = element.get(attribute)
                if name is not None and not _inside(name, base_dir):
                    raise SceneryError(f'{what}: {attribute}={quoted(name)} of <{element.tag}> '
                                       "lies outside the scenery's own folder")
        try:
            if base_dir is None:
                spec = mujoco.MjSpec.from_string(text.decode('utf-8'))
            else:
                spec = mujoco.MjSpec.from_file(self.path)
        except Exception as error:
            reason = ' '.join(str(error).split()).removeprefix('Error: ')
            raise SceneryError(f'{what} is not valid MJCF: {reason}') from None
        if spec.joints:
            raise SceneryError(f'{what} has joints ({len(spec.joints)}); scenery is static',
                               unsupported=True)
        return spec, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)

    def attach(self, spec):
        """Add the obstacles to a world's spec, their names under SCENERY_PREFIX."""
        frame = spec.worldbody.add_frame(pos=self._position, quat=self._orientation)
        spec.attach(self._spec.copy(), frame=frame, prefix=SCENERY_PREFIX)


def _inside(name, base_dir):
    """Return True if a file an MJCF scenery names lies in its folder (a text names none)."""
    if base_dir is None or os.path.isabs(name) or '..' in name.replace('\\', '/').split('/'):
        return False
    path = os.path.realpath(os.path.join(base_dir, name))
    folder = os.path.realpath(base_dir)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)
