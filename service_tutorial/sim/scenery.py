"""
Scenery: static obstacles from a file, part of the world's scene rather than a model.

A URDF whose root link is fixed to the link `world` (the builder's anchored robot), with fixed
joints only and no plugins, or an MJCF file without joints and without <include>. Its bodies
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


class Scenery:
    """The static obstacles of one file, ready to be added to every spec the world builds."""

    def __init__(self, path, *, package_resolver=None):
        """Read and check a URDF or MJCF file of static obstacles, or raise WorldError."""
        self.path = os.path.abspath(path)
        try:
            with open(self.path, 'rb') as scenery_file:
                text = scenery_file.read(MAX_MODEL_XML_BYTES + 1)
        except OSError as error:
            raise WorldError(f'cannot read scenery file {quoted(path)}: {error.strerror}') \
                from None
        what = f'scenery file {quoted(path)}'
        if len(text) > MAX_MODEL_XML_BYTES:
            raise WorldError(f'{what} is larger than {MAX_MODEL_XML_BYTES} bytes')
        try:
            root = parse_xml(text, what)
        except UrdfError as error:
            raise WorldError(str(error)) from None
        tag = etree.QName(root).localname
        if tag == 'robot':
            self._spec, self._position, self._orientation = self._from_urdf(text, what,
                                                                            package_resolver)
        elif tag == 'mujoco':
            self._spec, self._position, self._orientation = self._from_mjcf(root, what)
        else:
            raise WorldError(f'{what} is neither URDF nor MJCF: its root element is <{tag}>')
        try:
            probe = mujoco.MjSpec()
            self.attach(probe)
            probe.compile()
        except Exception as error:
            reason = ' '.join(str(error).split()).removeprefix('Error: ')
            raise WorldError(f'{what} does not compile: {reason}') from None

    def _from_urdf(self, text, what, package_resolver):
        try:
            description = load_urdf(text, base_dir=os.path.dirname(self.path),
                                    package_resolver=package_resolver)
        except UrdfError as error:
            raise WorldError(f'{what}: {error}') from None
        if not description.anchored:
            raise WorldError(f'{what} must fix its root link {quoted(description.root_link)} '
                             "to the link 'world' with a fixed joint")
        if description.joints:
            raise WorldError(f'{what} has moving joints ({", ".join(description.joints)}); '
                             'scenery is static')
        if description.plugins:
            raise WorldError(f'{what} carries plugins; scenery is static')
        return (description.spec, description.root_position, description.root_orientation)

    def _from_mjcf(self, root, what):
        if next(root.iter('include'), None) is not None:
            raise WorldError(f'{what} has an <include>, which scenery files may not have')
        try:
            spec = mujoco.MjSpec.from_file(self.path)
        except Exception as error:
            reason = ' '.join(str(error).split()).removeprefix('Error: ')
            raise WorldError(f'{what} is not valid MJCF: {reason}') from None
        if spec.joints:
            raise WorldError(f'{what} has joints ({len(spec.joints)}); scenery is static')
        return spec, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)

    def attach(self, spec):
        """Add the obstacles to a world's spec, their names under SCENERY_PREFIX."""
        frame = spec.worldbody.add_frame(pos=self._position, quat=self._orientation)
        spec.attach(self._spec.copy(), frame=frame, prefix=SCENERY_PREFIX)
