"""
What the world node asks of the ROS face of one plugin: the protocol every face meets.

A face gives one plugin of a model its topics. The world node makes the faces of a model when
the model is spawned (model_interface.ModelInterface): each works out its topics' names then,
so that a bad one refuses the spawn, and makes them in make_topics(), once the spawn is
answered. From then on the node hands each face, at each tick, what concerns it: the
publication streams that fell due (publish), the commands that came since the last tick
(take_commands, for a face that declares takes_commands), and a look for subscribers once a
watcher's next_look comes. Faces inherit the defaults written here, so each says only
what it does.
"""

from typing import ClassVar, Protocol, runtime_checkable, Sequence


class Watcher(Protocol):
    """Something the node has look for subscribers now and then, in wall time."""

    next_look: float  # wall time at which look() has something to do

    def look(self, wall_time: float) -> None:
        """Switch what depends on subscribers on or off."""


@runtime_checkable
class PluginFace(Protocol):
    """
    The ROS face of one plugin of a model.

    A face is made as Face(node, world, model, plugin, namespace), namespace being the model's
    ('' or '/a/b'), and makes the plugin's topics on node in make_topics().
    """

    streams: ClassVar[tuple] = ()  # the node's publication streams the face publishes on
    takes_commands: ClassVar[bool] = False  # whether the node hands it take_commands()
    topics: Sequence[str] = ()  # the names of the topics make_topics() makes

    @classmethod
    def applies_to(cls, plugin) -> bool:
        """Tell whether this kind of face serves a plugin."""
        raise NotImplementedError

    @property
    def watchers(self) -> Sequence[Watcher]:
        """Return what the node has look for subscribers."""
        return ()

    def make_topics(self) -> None:
        """Make the face's topics on the node."""

    def publish(self, stream, now: float) -> None:
        """Publish the face's part of a stream that fell due at simulation time now."""

    def take_commands(self) -> None:
        """Hand the plugin the commands that came since the last tick."""

    def destroy(self) -> None:
        """Remove the face's topics from the node, if make_topics() made them."""
