"""Every ROS face meets the PluginFace protocol, and every plugin a robot carries has a face."""

from repository import model_path, TEST_MODELS, TINYBOT
from service_tutorial.sim.world import World
from service_tutorial.testing.spawns import spawn_file
from service_tutorial.world_node.faces import FACES
from service_tutorial.world_node.faces.face import PluginFace


def test_every_face_declares_the_protocol_and_fills_in_what_it_does():
    for face in FACES:
        assert PluginFace in face.__mro__, f'{face.__name__} does not declare PluginFace'
        # The protocol's applies_to() only raises: each kind must say which plugins it serves.
        assert face.applies_to.__func__ is not PluginFace.applies_to.__func__, face.__name__
        assert isinstance(face.streams, tuple) and isinstance(face.takes_commands, bool)


def test_every_plugin_of_the_shipped_and_gazebo_robots_has_a_face():
    world = World()
    spawn_file(world, 'tinybot', TINYBOT)
    spawn_file(world, 'skidbot', model_path('skidbot_ros1', TEST_MODELS),
               position=(3.0, 0.0, 0.1))
    carried = [plugin for model in world.models.values() for plugin in model.plugins]
    assert {type(plugin).__name__ for plugin in carried} >= {
        'DiffDrive', 'SkidSteer', 'RaySensor', 'CameraSensor', 'ImuSensor'}
    for plugin in carried:
        faces = [face.__name__ for face in FACES if face.applies_to(plugin)]
        assert faces, f'{type(plugin).__name__} has no ROS face'
    drive = world.models['tinybot'].drive()
    assert [face.__name__ for face in FACES if face.applies_to(drive)] == [
        'DriveFace', 'OdomTfFace']
