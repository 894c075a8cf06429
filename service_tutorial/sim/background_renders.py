"""
Camera frames rendered on a thread of their own, so that the world's thread never waits for one.

Without a GPU, MuJoCo renders in software (Mesa's llvmpipe): 20 to 90 ms for a 320x240 frame
on two busy cores, a second for a 4096x3072 one. A world that renders in the background
(World(background_rendering=True), as the world node's does) takes a camera's snapshot of the
scene where its reading falls due, on the stepping thread (mjv_updateScene copies the
geometry, well under a millisecond), and one rendering thread turns the snapshots into images,
one at a time, while the world steps and answers: MuJoCo releases the GIL while it renders.
All cameras draw with one GL context, kept for the world's life: making one takes half a second
in software, and MuJoCo's rendering context for each new model (made on the rendering thread,
but holding the GIL for 25 to 90 ms) is made once per model for all cameras, not per camera.
deliver(), which the world's owner calls on the stepping thread (the world node does each time
it publishes), hands the earliest finished frame to its camera, stamped with the time of its
snapshot.
Without a GPU, rendering would take every core from the world's thread: the rendering thread and
Mesa's software rasterizer threads (llvmpipe's) run RENDER_NICENESS nicer than the rest of the
process, so that the world steps and answers first and frames take the CPU that is left.
A camera whose previous frame is still being rendered when the next falls due skips that
reading; the world's log says so once per camera.
"""

from concurrent.futures import ThreadPoolExecutor
import os
import threading

from service_tutorial.sim.core_logs import core_logger
from service_tutorial.sim.rendering import Drawing

_logger = core_logger(__name__)

# How much nicer (in Linux nice levels, 0 to 19) rendering runs than the world's thread.
RENDER_NICENESS = 10
SOFTWARE_RASTERIZER_THREADS = 'llvmpipe-'  # Mesa names them llvmpipe-0, llvmpipe-1, ...


def make_nicer(thread_id):
    """Lower a thread's CPU priority by RENDER_NICENESS (Linux); do nothing where not allowed."""
    try:
        niceness = os.getpriority(os.PRIO_PROCESS, thread_id)
        os.setpriority(os.PRIO_PROCESS, thread_id, min(19, niceness + RENDER_NICENESS))
    except (AttributeError, OSError):  # no such thread any more, or no per-thread priorities
        pass


def make_rendering_nicer():
    """Lower the priority of the calling thread and of the software rasterizer's threads."""
    make_nicer(threading.get_native_id())
    try:
        threads = os.listdir('/proc/self/task')
    except OSError:
        return
    for thread_id in threads:
        try:
            with open(f'/proc/self/task/{thread_id}/comm') as comm:
                name = comm.read()
        except OSError:
            continue
        if name.startswith(SOFTWARE_RASTERIZER_THREADS):
            make_nicer(int(thread_id))


class BackgroundRenders:
    """The frames being rendered, each for its camera, on one rendering thread."""

    def __init__(self):
        """Start with no thread: it is made for the first frame."""
        self._pool = None
        self._drawing = Drawing()  # draws on the rendering thread only
        self._pending = []  # (camera, future of the image, simulation time of the snapshot)

    def submit(self, camera, render, taken_at):
        """Draw a camera's snapshot on the rendering thread: render(drawing) returns the image."""
        if self._pool is None:
            self._drawing.make_gl_context()  # starts the software rasterizer's threads, if any
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix='camera_render',
                                            initializer=make_rendering_nicer)
        self._pending.append((camera, self._pool.submit(render, self._drawing), taken_at))

    def busy(self, camera):
        """Tell whether a frame of the camera is still being rendered or waits to be handed on."""
        return any(pending is camera for pending, _, _ in self._pending)

    def deliver(self):
        """Hand the earliest finished frame, if any, to its camera (frame_rendered)."""
        # One frame a call: publishing a large frame takes tens of milliseconds, and the
        # world's thread answers calls between two ticks; the other frames wait their turn.
        finished = next((entry for entry in self._pending if entry[1].done()), None)
        if finished is None:
            return
        self._pending.remove(finished)
        camera, future, taken_at = finished
        error = future.exception()
        if error is not None:  # the world goes on; the camera tries again next time
            _logger.error("camera '%s' could not draw its frame of %.3f s: %s",
                          camera.config.name, taken_at, error)
            return
        camera.frame_rendered(future.result(), taken_at)

    def forget(self, camera):
        """Wait for the camera's frame in progress, if any, and drop it: the camera goes."""
        for pending, future, _ in self._pending:
            if pending is camera:
                future.exception()  # waits; a frame nobody will see may fail quietly
        self._pending = [entry for entry in self._pending if entry[0] is not camera]

    def close(self):
        """Wait for the frames in progress, end the rendering thread and free its GL context."""
        for camera, _, _ in list(self._pending):
            self.forget(camera)
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
        self._drawing.close()
