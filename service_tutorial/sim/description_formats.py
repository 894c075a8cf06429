"""
The description formats the world reads, each behind the same small interface.

A format has a name (as SpawnEntity names formats), the root element that tells its text
apart, the file extensions it goes by, and a load() that builds a RobotDescription from its
text or refuses it with a DescriptionError (an AssetError for a file it names). A new format
is one more entry of FORMATS; the reader of robot files (robot_files.py) and the world's
description cache (description_cache.py) take it from there.
"""

from dataclasses import dataclass

from service_tutorial.sim.description import UrdfError
from service_tutorial.sim.mjcf import load_mjcf
from service_tutorial.sim.urdf.builder import load_urdf
from service_tutorial.sim.validation import DescriptionError


@dataclass(frozen=True)
class DescriptionFormat:
    """A format robots are described in: how to tell it and how to build it."""

    name: str  # 'urdf', 'mjcf'
    root: str  # the tag of its root element
    extensions: tuple  # of its files, lower case, xacro's aside
    name_attribute: str  # the root's attribute that names the robot
    builder: object  # (text, base_dir, package_resolver, timestep) -> RobotDescription

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


URDF = DescriptionFormat(name='urdf', root='robot', extensions=('.urdf',),
                         name_attribute='name', builder=_build_urdf)
MJCF = DescriptionFormat(name='mjcf', root='mujoco', extensions=('.xml', '.mjcf'),
                         name_attribute='model', builder=_build_mjcf)
FORMATS = {description_format.name: description_format for description_format in (URDF, MJCF)}
