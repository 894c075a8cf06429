"""
Watching which files a request makes the process open: an audit hook and inotify.

Used by the hostile-input tests (through the world node) and the mesh tests (the loaders
alone); no ROS here.
"""

import ctypes
import os
import struct
import sys
import threading


class FileOpens:
    """
    Record opens of chosen files: by Python code (an audit hook) and by any code (inotify).

    The audit hook sees open(), io.open() and os.open() from every thread of this process; it
    cannot be removed, so it only records while a FileOpens is active. inotify also sees the C
    libraries (MuJoCo, libxml2) open the files in the directories it watches.
    """

    IN_ACCESS, IN_OPEN = 0x1, 0x20
    _active = None
    _hook_lock = threading.Lock()
    _hook_added = False

    def __init__(self, watched_paths, watched_directory):
        self.watched = {os.path.realpath(path) for path in watched_paths}
        self.directory = watched_directory
        self.python_opens = []
        self.inotify_opens = []

    @classmethod
    def _audit(cls, event, args):
        active = cls._active
        if active is None or event != 'open' or not args:
            return
        path = args[0]
        if isinstance(path, (str, bytes)):
            active.python_opens.append(os.fsdecode(path))

    def __enter__(self):
        with FileOpens._hook_lock:
            if not FileOpens._hook_added:
                sys.addaudithook(FileOpens._audit)
                FileOpens._hook_added = True
        self._libc = ctypes.CDLL(None, use_errno=True)
        self._inotify = self._libc.inotify_init1(os.O_NONBLOCK | os.O_CLOEXEC)
        assert self._inotify >= 0, os.strerror(ctypes.get_errno())
        watch = self._libc.inotify_add_watch(self._inotify, os.fsencode(self.directory),
                                             self.IN_OPEN | self.IN_ACCESS)
        assert watch >= 0, os.strerror(ctypes.get_errno())
        FileOpens._active = self
        return self

    def __exit__(self, *exc_info):
        FileOpens._active = None
        try:
            events = os.read(self._inotify, 1 << 16)
        except BlockingIOError:
            events = b''
        finally:
            os.close(self._inotify)
        while events:
            _, _, _, length = struct.unpack_from('iIII', events)
            name = events[16:16 + length].rstrip(b'\0')
            self.inotify_opens.append(os.path.join(self.directory, os.fsdecode(name)))
            events = events[16 + length:]

    def opened(self):
        """Return the watched files that were opened, by either account."""
        python = {os.path.realpath(path) for path in self.python_opens if path}
        return sorted((python | set(self.inotify_opens)) & self.watched)


def write_canary_files(folder):
    """Write files a leaky loader would happily read: a DTD, a text file and a mesh."""
    paths = {'dtd': folder / 'secret.dtd', 'text': folder / 'secret.txt',
             'mesh': folder / 'secret.obj', 'mjcf': folder / 'control.xml'}
    paths['dtd'].write_text('<!ENTITY leak "TOP-SECRET">')
    paths['text'].write_text('TOP-SECRET')
    paths['mesh'].write_text('v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n'
                             'f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n')
    paths['mjcf'].write_text('<mujoco><asset><mesh file="secret.obj"/></asset><worldbody>'
                             '<geom type="mesh" mesh="secret"/></worldbody></mujoco>')
    return {kind: str(path) for kind, path in paths.items()}


def write_hostile_meshes(share, canary):
    """
    Write meshes into an allowed package share that lead to the canary text file outside it.

    A Collada file whose texture and an OBJ file whose material library are links, beside
    them, to the canary, and a Collada file whose DOCTYPE declares the canary an external
    entity: a loader that followed any of these would read it. Return the paths in the share.
    """
    meshes = share / 'meshes'
    meshes.mkdir(parents=True, exist_ok=True)
    for name in ('texture.png', 'materials.mtl'):
        os.symlink(canary['text'], meshes / name)
    with open(canary['mesh']) as box_file:
        obj_body = box_file.read()
    (meshes / 'textured.dae').write_text(
        '<?xml version="1.0"?><COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" '
        'version="1.4.1"><asset><unit meter="1"/></asset>'
        '<library_images><image id="img"><init_from>texture.png</init_from></image>'
        '</library_images><library_effects><effect id="fx"><profile_COMMON>'
        '<newparam sid="surface"><surface type="2D"><init_from>img</init_from></surface>'
        '</newparam><newparam sid="sampler"><sampler2D><source>surface</source></sampler2D>'
        '</newparam><technique sid="common"><lambert><diffuse>'
        '<texture texture="sampler" texcoord="uv"/></diffuse></lambert></technique>'
        '</profile_COMMON></effect></library_effects><library_materials>'
        '<material id="mat"><instance_effect url="#fx"/></material></library_materials>'
        '<library_geometries><geometry id="g"><mesh><source id="p"><float_array id="pa" '
        'count="12">0 0 0 1 0 0 0 1 0 0 0 1</float_array><technique_common><accessor '
        'source="#pa" count="4" stride="3"><param name="X" type="float"/><param name="Y" '
        'type="float"/><param name="Z" type="float"/></accessor></technique_common></source>'
        '<vertices id="v"><input semantic="POSITION" source="#p"/></vertices>'
        '<triangles count="4" material="m"><input semantic="VERTEX" source="#v" offset="0"/>'
        '<p>0 2 1 0 1 3 0 3 2 1 2 3</p></triangles></mesh></geometry></library_geometries>'
        '<library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g">'
        '<bind_material><technique_common><instance_material symbol="m" target="#mat"/>'
        '</technique_common></bind_material></instance_geometry></node></visual_scene>'
        '</library_visual_scenes><scene><instance_visual_scene url="#s"/></scene></COLLADA>')
    (meshes / 'entity.dae').write_text(
        '<?xml version="1.0"?><!DOCTYPE COLLADA [<!ENTITY leak SYSTEM '
        f'"file://{canary["text"]}">]><COLLADA '
        'xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">'
        '<asset><contributor><author>&leak;</author></contributor></asset></COLLADA>')
    (meshes / 'materials.obj').write_text(f'mtllib materials.mtl\nusemtl secret\n{obj_body}')
    return ('meshes/textured.dae', 'meshes/entity.dae', 'meshes/materials.obj')
