"""MuJoCo's interactive viewer on the world (gui:=true), kept on the world's current model."""


class PassiveViewer:
    """MuJoCo's passive viewer, opened again on every new model; off, every call does nothing."""

    def __init__(self, world, logger, *, enabled):
        """Open the viewer on world if enabled; logger hears why it could not open."""
        self.world = world
        self.logger = logger
        self.enabled = enabled
        self.handle = None
        self.reopen()

    def reopen(self):
        """(Re)open the viewer on the current model: spawns, deletes and loads rebuild it."""
        if not self.enabled:
            return
        import mujoco.viewer
        self.close()
        try:
            self.handle = mujoco.viewer.launch_passive(self.world.model, self.world.data)
        except Exception as error:  # no display, no OpenGL
            self.enabled = False
            self.logger.error(f'gui:=true but the viewer could not open: {error}')

    def sync(self):
        """Show the world's current state."""
        if self.handle is not None and self.handle.is_running():
            self.handle.sync()

    def close(self):
        """Close the viewer's window."""
        if self.handle is not None:
            self.handle.close()
            self.handle = None
