"""
The standard's GetSpawnables: the robot files a spawn uri may name, what each is, its bounds.

Offered are the robot files of every installed ament package (this one's models/ among them):
.urdf, .xacro, MJCF and SDF files and SDF model folders in its share's urdf/, models/, mjcf/ and
sdf/ folders and theirs below, each by the package:// uri SpawnEntity takes as it is
(spawnable_files.py finds and reads them). A Spawnable's description names the robot and its drives
and sensors with the topics a spawn without a namespace gives them ('tinybot: a diff-drive on
cmd_vel, odom, joint_states; a laser on scan'), and says when it is fixed to the world; its bounds
are the box GetEntityBounds gives the spawned entity, found by compiling the robot alone: the
world's own model is not touched. The world's scenery file (yard.urdf by default) is not offered:
it is already in the world as its walls and floor, and a copy spawned on top of it would only
overlap them. An installed .xacro file is expanded with its default arguments, as a spawn by its
uri expands it; one that is only macros or properties, and any file that does not load, is left out
and counted in the message. A request's sources add folders under the same rules as a spawn uri; a
source that is refused is named in the message with the reason, and the answer is still RESULT_OK,
as the standard has it ("not fatal").
"""

import os
import time

from geometry_msgs.msg import Vector3
from service_tutorial.sim import plugins
from service_tutorial.sim.validation import WorldError
from service_tutorial.world_node.answers import standard_answer
from service_tutorial.world_node.faces import FACES
from service_tutorial.world_node.packages import installed_shares, package_share
from service_tutorial.world_node.standard.spawnable_files import FileWalk, LeftOut
from service_tutorial.world_node.standard.spawnable_files import MAX_SOURCES, NOT_READ
from service_tutorial.world_node.standard.spawnable_files import READING_SECONDS
from service_tutorial.world_node.standard.spawnable_files import RobotFileReader
from service_tutorial.world_node.standard.spawnable_files import source_folder
from service_tutorial.world_node.standard.spawnable_files import SourceRefused
from simulation_interfaces.msg import Bounds, SimulatorFeatures, Spawnable
from simulation_interfaces.srv import GetSpawnables

# How many left-out files the message names; it counts them all.
NAMED_LEFT_OUT = 5


class SpawnableServices:
    """The standard's GetSpawnables of the world node (node.MujocoWorld)."""

    FEATURES = (SimulatorFeatures.SPAWNABLES,)

    def __init__(self, node, *, package_share=package_share, shares=installed_shares):
        """Serve get_spawnables relative to node's namespace, leaving out the world's scenery."""
        self.node = node
        self.shares = shares
        self.reader = RobotFileReader(package_share, self.plugin_words)
        self.get_spawnables_srv = node.serve(
            GetSpawnables, 'get_spawnables', self.get_spawnables_callback)

    def get_spawnables_callback(self, request, response):
        """List the robot files of the installed packages and of the sources asked for."""
        notes = standard_answer(
            self.node, 'GetSpawnables', response.result,
            self.node.holding_time(lambda: self._list(request.sources, response)))
        if notes:
            response.result.error_message = 'GetSpawnables: ' + '; '.join(notes)
        return response

    def _list(self, sources, response):
        """Fill in the response's spawnables; return the notes for its message."""
        notes = []
        walk = self._walk(sources, notes)
        left_out = [LeftOut(uri, 'it is a link that leads outside the share folder of its '
                            'package') for uri in walk.links_out]
        response.spawnables = []
        deadline = time.monotonic() + READING_SECONDS
        not_read = 0
        current = self.node.world_loader.current
        scenery = os.path.realpath(current.world.scenery) if current and current.world.scenery \
            else None
        for uri, path in walk.found.items():
            if path == scenery:
                continue
            offer = self.reader.read(uri, path, deadline=deadline)
            if offer is NOT_READ:
                not_read += 1
            elif isinstance(offer, LeftOut):
                left_out.append(offer)
            elif offer is not None:
                response.spawnables.append(Spawnable(
                    uri=offer.uri, description=offer.description,
                    spawn_bounds=_bounds(offer.box)))
        return notes + _notes(walk, left_out, not_read)

    def _walk(self, sources, notes):
        """Return the FileWalk of the sources and the installed packages; note what is refused."""
        shares = self.shares()
        walk = FileWalk()
        sources = list(sources)
        if len(sources) > MAX_SOURCES:
            notes.append(f'{len(sources)} sources are more than {MAX_SOURCES}; the '
                         f'{len(sources) - MAX_SOURCES} after the first {MAX_SOURCES} are not '
                         'read')
            sources = sources[:MAX_SOURCES]
        for source in sources:
            try:
                walk.walk(*source_folder(source, shares))
            except SourceRefused as refusal:
                notes.append(str(refusal))
        for package, share in shares.items():
            walk.walk_package(package, share)
        return walk

    def plugin_words(self, description):
        """Return a phrase for each plugin of a RobotDescription: 'a laser on scan'."""
        words = []
        for setup in description.plugins:
            plugin = plugins.plugin_class(setup.kind)(setup.config, setup.block)
            topics = []
            for face_kind in FACES:
                if face_kind.applies_to(plugin):
                    try:
                        face = face_kind(self.node, None, None, plugin, '')
                    except WorldError:  # a namespace the spawn would refuse
                        continue
                    topics.extend(face.topics)
            article = 'an' if plugin.title[0] in 'AEIOUaeiou' else 'a'
            words.append(f'{article} {plugin.title} on {", ".join(topics)}' if topics
                         else f'{article} {plugin.title}')
        return words


def _notes(walk, left_out, not_read):
    """Return what the message says of the files left out, not read yet, or not looked at."""
    notes = []
    if left_out:
        named = '; '.join(f'{item.uri}: {item.reason}' for item in left_out[:NAMED_LEFT_OUT])
        more = (f'; and {len(left_out) - NAMED_LEFT_OUT} more'
                if len(left_out) > NAMED_LEFT_OUT else '')
        notes.append(f'{len(left_out)} robot files are left out: {named}{more}')
    if not_read:
        notes.append(f'{not_read} robot files are not read yet: reading new files takes at '
                     f'most {READING_SECONDS:g} s a call; ask again for them')
    if walk.cut_short:
        notes.append(f'the search stopped at its limits (at most {walk.max_files} robot files, '
                     f'{walk.max_entries} folder entries in one call): {walk.skipped} robot '
                     'files more are not listed')
    return notes


def _bounds(box):
    """Return the standard's Bounds of a box (lower, upper), TYPE_EMPTY for None."""
    if box is None:
        return Bounds(type=Bounds.TYPE_EMPTY)
    return Bounds(type=Bounds.TYPE_BOX, points=[
        Vector3(x=float(x), y=float(y), z=float(z)) for x, y, z in box])
