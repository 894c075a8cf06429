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
interface what concerns its faces at each tick, through a Roster of every model's faces.
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
        self.publishing = {}  # stream -> the faces that publish on it, once the topics are made
        self.watchers = []
        self.commanded = []  # the faces that take commands

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
                self.publishing.setdefault(stream, []).append(face)
        self.watchers = [watcher for face in self.faces for watcher in face.watchers]
        self.commanded = [face for face in self.faces if face.takes_commands]

    def remake_gz_topics(self):
        """Serve the gz faces' topics as the node's bridge says now (made, or still to make)."""
        for face in self.faces:
            if isinstance(face, GzFace):
                if self.topics_made:
                    face.remake_topics()
                else:
                    face.served = face.serve()

    def destroy(self):
        """Remove every topic of the model from the node."""
        for part in self._parts():
            part.destroy()
        self.faces, self.description = [], None
        self.publishing, self.watchers, self.commanded = {}, [], []


class Roster:
    """
    What the node asks of every model's faces at a tick, across models in spawn order.

    Made again whenever a model's topics are made or destroyed: at each tick a fleet's faces are
    called directly, without a call to each model in between (at real time with 50 robots, a
    tick called the models 150 times to reach them).
    """

    def __init__(self, interfaces):
        """Gather the faces of ModelInterfaces, in their order."""
        self.publishing = {}  # stream -> each face's publish(stream, now)
        self.take_commands = []  # each face's take_commands()
        self.watchers = []
        for interface in interfaces:
            for stream, faces in interface.publishing.items():
                self.publishing.setdefault(stream, []).extend(face.publish for face in faces)
            self.take_commands.extend(face.take_commands for face in interface.commanded)
            self.watchers.extend(interface.watchers)
