"""
The robots a world has built from their texts, kept so that the same text spawns again unbuilt.

Building a robot (parsing, checks, yourdfpy, the spec builder) took most of a spawn; a fleet
spawns one description many times. A description is kept under its text and the folder its
meshes resolve from, and used again only while its mesh files (and the files an SDF model
includes) are unchanged. A description with missing meshes is not kept: the files may turn up.
Spawning never changes a description: the world's spec attaches a copy of it. Within one
batch, a fleet's orders share one text: it is looked up and its meshes checked once
(for_batch()).
"""

import collections
import os

from service_tutorial.sim.description_formats import FORMATS

# Descriptions kept per world, the least recently spawned dropped first.
CACHED_DESCRIPTIONS = 16


def _file_stamps(description):
    """Return (path, modification time, size) of each file a description read, None if one went."""
    stamps = []
    for path in dict.fromkeys(description.mesh_files + description.source_files):
        try:
            status = os.stat(path)
        except OSError:
            return None
        stamps.append((path, status.st_mtime_ns, status.st_size))
    return tuple(stamps)


def _folder(base_dir):
    """
    Return what tells the folder meshes resolve from apart, whatever path leads to it.

    Its device and inode, which every path to it shares: one stat (3 us), where its real path
    took a stat of every part of the path (26 us for the package's models folder).
    """
    if not base_dir:
        return None
    try:
        status = os.stat(base_dir)
    except OSError:  # nothing resolves in a folder that is not there
        return os.path.abspath(base_dir)
    return status.st_dev, status.st_ino


class DescriptionCache:
    """Builds robot descriptions for one world, keeping the ones it may be asked for again."""

    def __init__(self, package_resolver, timestep, size=CACHED_DESCRIPTIONS):
        """Build as the world does: with its package resolver and for its timestep."""
        self._package_resolver = package_resolver
        self._timestep = timestep
        self._size = size
        self._kept = collections.OrderedDict()  # key -> (description, mesh stamps)

    def load(self, text, base_dir=None, model_format='urdf'):
        """Return the RobotDescription of a text in a format, or raise DescriptionError."""
        # The text itself is the key: Python hashes a str once and keeps the hash, and tells
        # an equal text by comparing, where a digest of it cost a pass of SHA-256 every time.
        key = (text if isinstance(text, str) else bytes(text), _folder(base_dir), model_format)
        kept = self._kept.pop(key, None)
        if kept is not None and _file_stamps(kept[0]) == kept[1]:
            self._kept[key] = kept
            return kept[0]
        description = FORMATS[model_format].load(
            text, base_dir=base_dir, package_resolver=self._package_resolver,
            timestep=self._timestep)
        stamps = _file_stamps(description)
        if not description.missing_meshes and stamps is not None:
            self._kept[key] = (description, stamps)
            while len(self._kept) > self._size:
                self._kept.popitem(last=False)
        return description

    def for_batch(self):
        """Return a loader for one batch: the same text object loads once, however often."""
        return _BatchLoader(self)


class _BatchLoader:
    """The cache's load, done once per text object and folder of one batch."""

    def __init__(self, cache):
        self._cache = cache
        self._loaded = {}  # (id of the text, base_dir) -> (text, description)

    def load(self, text, base_dir=None, model_format='urdf'):
        """Return the RobotDescription of a robot's text, as the cache's own load does."""
        key = (id(text), base_dir, model_format)
        loaded = self._loaded.get(key)
        if loaded is None or loaded[0] is not text:
            loaded = self._loaded[key] = (text, self._cache.load(text, base_dir, model_format))
        return loaded[1]
