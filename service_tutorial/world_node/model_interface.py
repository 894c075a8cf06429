"""
The ROS side of one model in the world: the turtle of turtlesim.

The world node makes a ModelInterface when it spawns a model and destroys it along with the
model. The interface keeps the model's ROS namespace and gives each plugin of the model its
face (faces/): every kind of face in FACES that applies to a plugin makes that plugin's topics;
a model with faces also gets its robot_description. Every topic's name is worked out and
checked when the interface is made, so that a name ROS would refuse refuses the spawn; the
topics themselves are made by make_topics(), which the node calls once the spawn is answered:
making them is most of a spawn's time (rclpy and the middleware take about 0.8 ms per topic,
eight for tinybot, where MuJoCo attaches it in about 1 ms). From then on the node hands the
interface what concerns its faces at each tick.
"""

from service_tutorial.world_node.faces import FACES
from service_tutorial.world_node.faces.gz_face import GzFace
from service_tutorial.world_node.ros_names import check_topic
from service_tutorial.world_node.tf_publishing import RobotDescriptionPublisher


class ModelInterface:
    """One model's namespace, the faces of its plugins and its robot_description."""

    def __init__(self, node, world, model, namespace, urdf):
        """
        Name a model's topics (namespace normalised: '' or '/a/b'); make_topics() makes them.

        urdf: the text robot_description carries; None (an MJCF model) for none.
        """
        self.model_name = model.name
        self.namespace = namespace
        self.topics_made = False
        self.faces = []
        self.description = None
        try:
            for kind in FACES:
                for plugin in model.plugins:
                    if kind.applies_to(plugin):
                        self.faces.append(kind(node, world, model, plugin, namespace))
            if self.faces and urdf is not None:  # for robot_state_publisher and RViz
                self.description = RobotDescriptionPublisher(node, namespace, urdf)
            for part in self._parts():
                for topic in part.topics:
                    check_topic(node, model.name, topic)
        except Exception:
            self.destroy()
            raise
        self._publishing = {}
        self.watchers = []
        self._commanded = []

    def _parts(self):
        return self.faces + ([self.description] if self.description is not None else [])

    def make_topics(self):
        """Make the model's topics; from now on the faces publish and take commands."""
        try:
            for part in self._parts():
                part.make_topics()
        except Exception:
            self.destroy()
            raise
        self.topics_made = True
        # Each stream calls only the faces that publish on it: a fleet has hundreds of faces.
        for face in self.faces:
            for stream in face.streams:
                self._publishing.setdefault(stream, []).append(face)
        self.watchers = [watcher for face in self.faces for watcher in face.watchers]
        self._commanded = [face for face in self.faces if face.takes_commands]

    def remake_gz_topics(self):
        """Serve the gz faces' topics as the node's bridge says now (made, or still to make)."""
        for face in self.faces:
            if isinstance(face, GzFace):
                if self.topics_made:
                    face.remake_topics()
                else:
                    face.served = face.serve()

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
        for part in self._parts():
            part.destroy()
        self.faces, self.description = [], None
        self._publishing, self.watchers, self._commanded = {}, [], []
