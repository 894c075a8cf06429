"""
Scenery: static obstacles from a file, part of the world's scene rather than a model.

A URDF whose root link is fixed to the link `world` (the builder's anchored robot), with fixed
joints only and no plugins, or an MJCF file without joints, without <include> and without files
outside its own folder (a scenery given as text names no file at all); or the static models of
an SDF world, each where the world puts it, with the world's own ground (or none) in place of
the plane. Its bodies are welded to the world, so they collide and are seen by lasers and
cameras, but they are not a model: get_model_list does not name them, and no service moves or
deletes them.
"""

import os

import mujoco
from service_tutorial.sim import frames
from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.robot_files import read_path, read_text
from service_tutorial.sim.sdf.builder import build as build_sdf
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.urdf.hardened_xml import parse_xml
from service_tutorial.sim.validation import quoted
from service_tutorial.sim.validation import Reason
from service_tutorial.sim.validation import SCOPE_SEPARATOR
from service_tutorial.sim.validation import WorldError

# Names of the scenery's elements in the world's model; no model name holds a '/'.
SCENERY_PREFIX = 'scenery/'
NOT_STATIC = Reason.UNSUPPORTED_CONTENT  # what scenery may not hold: joints, plugins...
# The formats of a scenery file; an SDF world's static models are its scenery (from_sdf).
SCENERY_FORMATS = ('urdf', 'mjcf')


class SceneryError(WorldError):
    """A scenery the world refuses: unreadable, or (UNSUPPORTED_CONTENT) not static."""


class Scenery:
    """The static obstacles of one file, ready to be added to every spec the world builds."""

    own_ground = False  # an SDF world's scenery has its ground (or none) in it
    notes = ()  # what a user should know about how it was built: meshes left out
    missing_meshes = ()  # the uris of the meshes left out, each once

    def __init__(self, path, *, package_resolver=None):
        """Read and check a URDF or MJCF file of static obstacles, or raise SceneryError."""
        self.path = os.path.abspath(path)
        self._load(_read(read_path, self.path, what='scenery file', formats=SCENERY_FORMATS),
                   f'scenery file {quoted(path)}', package_resolver)

    @classmethod
    def from_text(cls, text, what, *, package_resolver=None):
        """Return the Scenery of a URDF or MJCF text that names no file, or raise SceneryError."""
        scenery = cls.__new__(cls)
        scenery.path = None
        scenery._load(_read(read_text, text, what, formats=SCENERY_FORMATS), what,
                      package_resolver)
        return scenery

    @classmethod
    def from_sdf(cls, world, what, *, package_resolver=None):
        """
        Return the Scenery of an SDF world's static models, where they stand (sdf/world.py).

        The world's ground is among them, or it has none; refuse as SceneryError.
        """
        scenery = cls.__new__(cls)
        scenery.path = None
        scenery.own_ground = True
        spec = mujoco.MjSpec()
        spec.copy_during_attach = True
        notes, missing = [], []
        for model, pose in world.static_models:
            try:
                description = build_sdf(model, package_resolver, scenery=True)
            except WorldError as error:
                raise SceneryError(f'{what}: {error}', error.reason) from None
            position, orientation = frames.compose(
                pose[0], pose[1], description.root_position, description.root_orientation)
            frame = spec.worldbody.add_frame(pos=position, quat=orientation)
            spec.attach(description.spec, frame=frame, prefix=model.name + SCOPE_SEPARATOR)
            notes += [f'model {quoted(model.name)}: {note}' for note in description.notes]
            missing += description.missing_meshes
        scenery.notes = tuple(notes)
        scenery.missing_meshes = tuple(dict.fromkeys(missing))
        scenery._spec = spec
        scenery._position, scenery._orientation = (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)
        scenery._check(what)
        return scenery

    def _load(self, source, what, package_resolver):
        if source.model_format == 'urdf':
            self._spec, self._position, self._orientation = self._from_urdf(
                source.text, what, source.base_dir, package_resolver)
        else:
            self._spec, self._position, self._orientation = self._from_mjcf(
                source.text, what, source.base_dir)
        self._check(what)

    def _check(self, what):
        """Refuse a scenery that does not compile."""
        try:
            probe = mujoco.MjSpec()
            self.attach(probe)
            probe.compile()
        except Exception as error:
            reason = ' '.join(str(error).split()).removeprefix('Error: ')
            raise SceneryError(f'{what} does not compile: {reason}',
                               Reason.DOES_NOT_COMPILE) from None

    def _from_urdf(self, text, what, base_dir, package_resolver):
        try:
            description = load_urdf(text, base_dir=base_dir, package_resolver=package_resolver)
        except UrdfError as error:
            raise SceneryError(f'{what}: {error}', Reason.NOT_PARSEABLE) from None
        if not description.anchored:
            raise SceneryError(f'{what} must fix its root link {quoted(description.root_link)} '
                               "to the link 'world' with a fixed joint", NOT_STATIC)
        if description.joints:
            raise SceneryError(f'{what} has moving joints ({", ".join(description.joints)}); '
                               'scenery is static', NOT_STATIC)
        if description.plugins:
            raise SceneryError(f'{what} carries plugins; scenery is static', NOT_STATIC)
        return (description.spec, description.root_position, description.root_orientation)

    def _from_mjcf(self, text, what, base_dir):
        root = parse_xml(text.encode('utf-8'), what)
        if next(root.iter('include'), None) is not None:
            raise SceneryError(f'{what} has an <include>, which scenery files may not have',
                               NOT_STATIC)
        for element in root.iter():
            for attribute in ('file', 'meshdir', 'texturedir', 'assetdir'):
                name = element.get(attribute)
                if name is not None and not _inside(name, base_dir):
                    raise SceneryError(f'{what}: {attribute}={quoted(name)} of <{element.tag}> '
                                       "lies outside the scenery's own folder",
                                       Reason.REFUSED_ASSET)
        try:
            spec = mujoco.MjSpec.from_string(text)
            if base_dir is not None:
                spec.modelfiledir = base_dir
        except Exception as error:
            reason = ' '.join(str(error).split()).removeprefix('Error: ')
            raise SceneryError(f'{what} is not valid MJCF: {reason}',
                               Reason.NOT_PARSEABLE) from None
        if spec.joints:
            raise SceneryError(f'{what} has joints ({len(spec.joints)}); scenery is static',
                               NOT_STATIC)
        return spec, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)

    def attach(self, spec):
        """Add the obstacles to a world's spec, their names under SCENERY_PREFIX."""
        frame = spec.worldbody.add_frame(pos=self._position, quat=self._orientation)
        spec.attach(self._spec.copy(), frame=frame, prefix=SCENERY_PREFIX)


def _read(reader, *arguments, **options):
    """Return the RobotSource a reader of robot_files.py gives, refusing as SceneryError."""
    try:
        return reader(*arguments, **options)
    except WorldError as error:
        raise SceneryError(str(error), error.reason) from None


def _inside(name, base_dir):
    """Return True if a file an MJCF scenery names lies in its folder (a text names none)."""
    if base_dir is None or os.path.isabs(name) or '..' in name.replace('\\', '/').split('/'):
        return False
    path = os.path.realpath(os.path.join(base_dir, name))
    folder = os.path.realpath(base_dir)
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)
