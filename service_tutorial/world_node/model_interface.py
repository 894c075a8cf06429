"""
The ROS side of one model in the world: the turtle of turtlesim.

The world node makes a ModelInterface when it spawns a model and destroys it along with the
model. The interface keeps the model's ROS namespace and gives each plugin of the model its
face (faces/): every kind of face in FACES that applies to a plugin makes that plugin's topics.
The node then hands the interface what concerns its faces at each tick.
"""

from service_tutorial.world_node.faces import FACES


class ModelInterface:
    """One model's namespace and the faces of its plugins."""

    def __init__(self, node, world, model, namespace):
        """Give a model just spawned its topics; namespace is normalised ('' or '/a/b')."""
        self.model_name = model.name
        self.namespace = namespace
        self.faces = []
        try:
            for kind in FACES:
                for plugin in model.plugins:
                    if kind.applies_to(plugin):
                        self.faces.append(kind(node, world, model, plugin, namespace))
        except Exception:
            self.destroy()
            raise
        # Each stream calls only the faces that publish on it: a fleet has hundreds of faces.
        self._publishing = {}
        for face in self.faces:
            for stream in face.streams:
                self._publishing.setdefault(stream, []).append(face)
        self.watchers = [watcher for face in self.faces for watcher in face.watchers]
        self._commanded = [face for face in self.faces if face.takes_commands]

    def publish(self, stream, now):
        """Publish each plugin's part of a stream that fell due at simulation time now."""
        for face in self._publishing.get(stream, ()):
            face.publish(stream, now)

    def take_commands(self):
        """Let the faces that take commands (a drive's cmd_vel) take those that came."""
        for face in self._commanded:
            face.take_commands()

    def destroy(self):
        """Remove every topic of the model from the node."""
        for face in self.faces:
            face.destroy()
        self.faces = []
