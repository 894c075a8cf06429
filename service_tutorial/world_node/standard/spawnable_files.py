"""
The robot files of installed ament packages that a spawn uri may name, found and read once.

A robot file lies in a package share's urdf/, models/, mjcf/ or sdf/ folder (or a folder a request
names as a source), at most MAX_DEPTH folders below it: a .urdf, a .xacro expanded with its default
arguments, an MJCF .xml/.mjcf whose root is <mujoco>, an SDF .sdf, or an SDF model folder (one with
a model.config, offered as the folder, which is not looked into). A file is read and built by the
same reader and the same format loader as a spawn by its uri (sim/robot_files.py,
sim/description_formats.py), so a file is offered exactly when a spawn would take it, and one left
out says the spawn's own reason. The same roots as a spawn uri's hold: a source is
package://<package>/<folder> or file://<folder> in an installed share, with no '..'; links to
folders are not followed, a file whose link leads out of its share is left out unread. Reading a
file (expanding, building, compiling it alone) is kept under its uri, real path, modification time
and size, so a second call costs only the walk; a call reads new files for READING_SECONDS at most
and leaves the rest to the next, so a world with many packages is not held up for long. (A xacro
file whose includes change while it does not is read again only once it changes too.) No rclpy: the
words for a robot's plugins come from the caller.
"""

import collections
from dataclasses import dataclass
import itertools
import math
import os
import time

from service_tutorial.sim import bounds
from service_tutorial.sim.description_formats import FORMATS
from service_tutorial.sim.package_files import confined_path, PackageFileError, within
from service_tutorial.sim.robot_files import file_model_name, read_uri
from service_tutorial.sim.sdf.paths import MODEL_CONFIG
from service_tutorial.sim.urdf.hardened_xml import parse_xml
from service_tutorial.sim.validation import Reason, WorldError

ROBOT_FOLDERS = ('urdf', 'models', 'mjcf', 'sdf')
URDF_EXTENSIONS = ('.urdf', '.xacro')
MJCF_EXTENSIONS = ('.xml', '.mjcf')
SDF_EXTENSIONS = ('.sdf',)
MAX_DEPTH = 3  # folders below a robot folder or a source
MAX_SOURCES = 32
MAX_FILES = 500  # robot files one call reads or takes from the cache
MAX_ENTRIES = 20000  # folder entries one call looks at
CACHED_FILES = 2000
# Wall time one call spends reading files it has not read before; the rest wait for a next call.
READING_SECONDS = 5.0
# What read() returns for a file left for a next call.
NOT_READ = 'not read'


class SourceRefused(Exception):
    """A source folder that is not read; the message names it and says why."""


@dataclass(frozen=True)
class RobotFileOffer:
    """A robot file to offer: its uri, what it is, and its box in its own frame (or None)."""

    uri: str
    description: str
    box: tuple  # (lower, upper) corners, or None: no collision geometry


@dataclass(frozen=True)
class LeftOut:
    """A robot file that is not offered, and why."""

    uri: str
    reason: str


def source_folder(source, shares):
    """
    Return (package, real share, real folder) of a source, or raise SourceRefused.

    shares: {package: real share folder} of the installed packages. A source is refused by the
    rules of a spawn uri (sim/package_files.py).
    """
    try:
        folder = confined_path(source, shares.get, folder=True, what='source')
    except PackageFileError as error:
        raise SourceRefused(str(error)) from None
    package, share = max(((package, share) for package, share in shares.items()
                          if within(folder, share)), key=lambda held: len(held[1]))
    return package, share, folder


class FileWalk:
    """The robot files of one call, found folder by folder within the call's limits."""

    def __init__(self, max_files=MAX_FILES, max_entries=MAX_ENTRIES):
        """Find at most max_files files, looking at most at max_entries folder entries."""
        self.found = {}  # uri -> real path, in the order found
        self.links_out = []  # uris of files whose links lead out of their share
        self.skipped = 0  # robot files past max_files
        self.max_files = max_files
        self.max_entries = max_entries
        self._entries_left = max_entries

    @property
    def cut_short(self):
        """Tell whether a limit stopped the walk."""
        return self.skipped > 0 or self._entries_left < 0

    def walk_package(self, package, share):
        """Add the robot files of a package's (real) share: its urdf/, models/, mjcf/, sdf/."""
        for name in ROBOT_FOLDERS:
            folder = os.path.join(share, name)
            if os.path.isdir(folder) and not os.path.islink(folder):
                self.walk(package, share, folder)

    def walk(self, package, share, folder, depth=MAX_DEPTH):
        """Add the robot files in a folder of a package's (real) share and its subfolders."""
        if self._entries_left < 0:
            return
        try:
            with os.scandir(folder) as listing:
                # One more than the walk may look at tells that the limit cut the folder short.
                entries = list(itertools.islice(listing, self._entries_left + 1))
        except OSError:
            return
        self._entries_left -= len(entries)
        if self._entries_left < 0:
            return
        if any(entry.name == MODEL_CONFIG for entry in entries):
            self._add(package, share, folder)  # an SDF model folder: the folder is the robot
            return
        subfolders = []
        for entry in sorted(entries, key=lambda entry: entry.name):
            if entry.is_dir(follow_symlinks=False):
                subfolders.append(entry.path)
            elif entry.name.lower().endswith(URDF_EXTENSIONS + MJCF_EXTENSIONS + SDF_EXTENSIONS):
                self._add(package, share, entry.path)
        if depth > 0:
            for subfolder in subfolders:
                self.walk(package, share, subfolder, depth - 1)

    def _add(self, package, share, entry):
        uri = f'package://{package}/{os.path.relpath(entry, share)}'
        if uri in self.found or uri in self.links_out:
            return
        path = os.path.realpath(entry)
        if not within(path, share):
            self.links_out.append(uri)
        elif not os.path.exists(path):
            return
        elif len(self.found) >= self.max_files:
            self.skipped += 1
        else:
            self.found[uri] = path


class RobotFileReader:
    """Reads robot files into RobotFileOffers or LeftOuts, keeping each answer for next time."""

    def __init__(self, package_resolver, plugin_words, size=CACHED_FILES):
        """
        Read with package_resolver (package -> share) for meshes and includes.

        plugin_words(description) returns a phrase for each plugin of a RobotDescription
        ('a diff-drive on cmd_vel').
        """
        self._package_resolver = package_resolver
        self._plugin_words = plugin_words
        self._size = size
        # (uri, real path, mtime, size) -> RobotFileOffer, LeftOut or None
        self._kept = collections.OrderedDict()

    def read(self, uri, path, *, deadline=math.inf):
        """
        Return the RobotFileOffer of a file, its LeftOut, or None if it is no robot file.

        A file not read before is read only until time.monotonic() passes deadline: after it,
        NOT_READ.
        """
        try:
            status = os.stat(path)
        except OSError as error:
            return LeftOut(uri, f'it cannot be read: {error.strerror}')
        key = (uri, path, status.st_mtime_ns, status.st_size)
        if key in self._kept:
            self._kept.move_to_end(key)
            return self._kept[key]
        if time.monotonic() > deadline:
            return NOT_READ
        answer = self._read_new(uri, path)
        self._kept[key] = answer
        while len(self._kept) > self._size:
            self._kept.popitem(last=False)
        return answer

    def _read_new(self, uri, path):
        try:
            robot = read_uri(uri, self._package_resolver)
        except WorldError as error:
            if error.reason == Reason.UNSUPPORTED_FORMAT and path.lower().endswith(
                    MJCF_EXTENSIONS):
                return None  # an .xml file of another kind: no robot file
            return LeftOut(uri, _one_line(error))
        if robot.model_format == 'urdf' and parse_xml(robot.text.encode(), uri).find(
                'link') is None:
            return LeftOut(uri, 'it has no links: it is macros or properties for other files')
        try:
            description = FORMATS[robot.model_format].load(
                robot.text, base_dir=robot.base_dir, package_resolver=self._package_resolver)
        except WorldError as error:
            if error.reason == Reason.UNSUPPORTED_FORMAT and robot.model_format == 'sdf':
                return None  # an SDF world: LoadWorld's, no robot
            return LeftOut(uri, _one_line(error))
        try:  # compiled alone, as a spawn compiles it into the world
            box = bounds.description_box(description)
        except ValueError as error:  # MuJoCo's compiler
            return LeftOut(uri, f'it does not compile: {_one_line(error)}')
        name = description.robot_name or file_model_name(path)
        words = list(self._plugin_words(description)) or ['no drive or sensors']
        if robot.model_format == 'mjcf':
            words.insert(0, f'MJCF, {len(description.actuators)} actuators')
        if description.ignored_plugins:
            words.append(f'plugins not simulated: {", ".join(description.ignored_plugins)}')
        if description.anchored:
            words.append('fixed to the world')
        return RobotFileOffer(uri, f'{name}: {"; ".join(words)}', box)


def _one_line(error):
    text = str(error) or type(error).__name__
    return ' '.join(line.strip() for line in text.splitlines() if line.strip())
