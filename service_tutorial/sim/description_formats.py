"""
The description formats the world reads, each behind the same small interface.

A format has a name (as SpawnEntity names formats), the root element that tells its text
apart, the file extensions it goes by, the name it gives its robot, and a load() that builds a
RobotDescription from its text or refuses it with a DescriptionError (an AssetError for a file
it names). A format may have uri schemes of its own (SDF's model://) and model folders (SDF's,
with a model.config), which the reader of robot files asks it to find the file of. A new
format is one more entry of FORMATS; the reader of robot files (robot_files.py) and the world's
description cache (description_cache.py) take it from there.
"""

from dataclasses import dataclass
import os

from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.mjcf import load_mjcf
from service_tutorial.sim.sdf.builder import load_sdf
from service_tutorial.sim.sdf.paths import MODEL_CONFIG, model_file, SdfPaths
from service_tutorial.sim.sdf.paths import UriMissing, UriRefused
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.validation import DescriptionError, Reason, WorldError


@dataclass(frozen=True)
class DescriptionFormat:
    """A format robots are described in: how to tell it and how to build it."""

    name: str  # 'urdf', 'mjcf', 'sdf'
    root: str  # the tag of its root element
    extensions: tuple  # of its files, lower case, xacro's aside
    robot_name: object  # (root element) -> the name it gives its robot, or None
    builder: object  # (text, base_dir, package_resolver, timestep) -> RobotDescription
    uri_schemes: tuple = ()  # schemes of its own, which locate() resolves
    locate: object = None  # (uri, package_resolver) -> real path, or WorldError
    folder_file: object = None  # (folder, read_file) -> its model file's path, or None

    def load(self, text, *, base_dir=None, package_resolver=None, timestep=0.002):
        """Return the RobotDescription of a text, or raise DescriptionError naming the cause."""
        return self.builder(text, base_dir, package_resolver, timestep)


def _build_urdf(text, base_dir, package_resolver, timestep):
    try:
        return load_urdf(text, base_dir=base_dir, package_resolver=package_resolver,
                         timestep=timestep)
    except UrdfError as error:
        raise DescriptionError(str(error)) from None


def _build_mjcf(text, base_dir, package_resolver, timestep):
    return load_mjcf(text, base_dir=base_dir, package_resolver=package_resolver)


def _build_sdf(text, base_dir, package_resolver, timestep):
    # The reader of robot files reads what an SDF model includes; it imports this module.
    from service_tutorial.sim.robot_files import read_description_text
    return load_sdf(text, base_dir=base_dir, package_resolver=package_resolver,
                    read_file=read_description_text, timestep=timestep)


def _sdf_model_name(root):
    model = root.find('model')
    return None if model is None else model.get('name')


def _locate_sdf(uri, package_resolver):
    """Return the real path a model:// uri names, or refuse it."""
    try:
        return SdfPaths(package_resolver).locate(uri, None, 'uri')
    except (UriRefused, UriMissing) as error:
        raise WorldError(str(error), Reason.NO_RESOURCE) from None


def _sdf_folder_file(folder, read_file):
    """Return the SDF file a model folder's model.config names, or None if it has none."""
    config = os.path.join(folder, MODEL_CONFIG)
    if not os.path.isfile(config):
        return None
    try:
        return model_file(folder, read_file(config, MODEL_CONFIG))
    except UriRefused as error:
        raise WorldError(str(error), Reason.NO_RESOURCE) from None


URDF = DescriptionFormat(name='urdf', root='robot', extensions=('.urdf',),
                         robot_name=lambda root: root.get('name'), builder=_build_urdf)
MJCF = DescriptionFormat(name='mjcf', root='mujoco', extensions=('.xml', '.mjcf'),
                         robot_name=lambda root: root.get('model'), builder=_build_mjcf)
SDF = DescriptionFormat(name='sdf', root='sdf', extensions=('.sdf',),
                        robot_name=_sdf_model_name, builder=_build_sdf,
                        uri_schemes=('model',), locate=_locate_sdf,
                        folder_file=_sdf_folder_file)
FORMATS = {description_format.name: description_format
           for description_format in (URDF, MJCF, SDF)}
