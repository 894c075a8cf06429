"""
Camera frames rendered on a thread of their own, so that the world's thread never waits for one.

Without a GPU, MuJoCo renders in software (Mesa's llvmpipe): 20 to 90 ms for a 320x240 frame
on two busy cores, a second for a 4096x3072 one. A world that renders in the background
(World(background_rendering=True), as the world node's does) takes a camera's snapshot of the
scene where its reading falls due, on the stepping thread (mjv_updateScene copies the
geometry, well under a millisecond), and one rendering thread turns the snapshots into images,
one at a time, while the world steps and answers: MuJoCo releases the GIL while it renders.
deliver(), which the world's owner calls on the stepping thread (the world node does each time
it publishes), hands each finished frame to its camera, stamped with the time of its snapshot.
A camera whose previous frame is still being rendered when the next falls due skips that
reading; the world's log says so once per camera.
"""

from concurrent.futures import ThreadPoolExecutor

from service_tutorial.sim.core_logs import core_logger

_logger = core_logger(__name__)


class BackgroundRenders:
    """The frames being rendered, each for its camera, on one rendering thread."""

    def __init__(self):
        """Start with no thread: it is made for the first frame."""
        self._pool = None
        self._pending = []  # (camera, future of the image, simulation time of the snapshot)

    def submit(self, camera, render, taken_at):
        """Render a camera's snapshot (render() returns the image) on the rendering thread."""
        if self._pool is None:
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix='camera_render')
        self._pending.append((camera, self._pool.submit(render), taken_at))

    def busy(self, camera):
        """Tell whether a frame of the camera is still being rendered or waits to be handed on."""
        return any(pending is camera for pending, _, _ in self._pending)

    def deliver(self):
        """Hand each finished frame to its camera (frame_rendered), in the order taken."""
        if not self._pending:
            return
        finished = [entry for entry in self._pending if entry[1].done()]
        if not finished:
            return
        self._pending = [entry for entry in self._pending if not entry[1].done()]
        for camera, future, taken_at in finished:
            error = future.exception()
            if error is not None:  # the world goes on; the camera tries again next time
                _logger.error("camera '%s' could not draw its frame of %.3f s: %s",
                              camera.config.name, taken_at, error)
                continue
            camera.frame_rendered(future.result(), taken_at)

    def forget(self, camera):
        """Wait for the camera's frame in progress, if any, and drop it: the camera goes."""
        for pending, future, _ in self._pending:
            if pending is camera:
                future.exception()  # waits; a frame nobody will see may fail quietly
        self._pending = [entry for entry in self._pending if entry[0] is not camera]

    def close(self):
        """Wait for the frames in progress and end the rendering thread."""
        for camera, _, _ in list(self._pending):
            self.forget(camera)
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
