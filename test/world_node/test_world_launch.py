"""
The installed launch/world.launch.py under launch_testing, the way ROS packages test theirs.

launch_testing's pytest plugin runs generate_test_description(), waits for ReadyToTest, runs
the test cases below against the running world, and the post-shutdown ones once every process
has ended. launch and launch_testing come with a ROS 2 Jazzy install, not with the PyPI wheels:
there this file skips.
"""

import os
import unittest

from ament_index_python.packages import get_package_share_directory
from launched_graph import LaunchedGraphTestCase
import pytest
from rosgraph_msgs.msg import Clock
from service_tutorial.conversions import seconds_of
from srv_interfaces.srv import ControlTurningMessage, GetModelList

try:
    from launch import LaunchDescription
    from launch.actions import IncludeLaunchDescription
    from launch.launch_description_sources import PythonLaunchDescriptionSource
    import launch_testing.actions
    import launch_testing.asserts
except ImportError:
    pytest.skip('launch_testing is not installed (launch is not on PyPI)',
                allow_module_level=True)

# A busy machine may take this long to start the world (imports, the scene, tinybot).
START_UP_TIMEOUT = 60.0


@pytest.mark.launch_test
def generate_test_description():
    """Launch the world as fast as it can run, with the lesson's turning server."""
    launch_file = os.path.join(
        get_package_share_directory('service_tutorial'), 'launch', 'world.launch.py')
    world = IncludeLaunchDescription(
        PythonLaunchDescriptionSource(launch_file),
        launch_arguments={'real_time_factor': '0', 'turning_server': 'true'}.items())
    return LaunchDescription([world, launch_testing.actions.ReadyToTest()])


class TestTheLaunchedWorld(LaunchedGraphTestCase):
    """The world as a client meets it while the launch runs."""

    node_name = 'world_launch_test'

    def call(self, srv_type, name, request):
        client = self.node.create_client(srv_type, name)
        self.assertTrue(client.wait_for_service(timeout_sec=START_UP_TIMEOUT),
                        f'{name} did not appear')
        future = client.call_async(request)
        self.assertTrue(self.spin_until(future.done, 30.0), f'{name} did not answer')
        return future.result()

    def test_the_world_says_it_is_ready_with_the_arguments_given(self, proc_output):
        proc_output.assertWaitFor('MuJoCo world ready: tinybot, timestep 0.002 s, '
                                  'real_time_factor 0.0', timeout=START_UP_TIMEOUT)

    def test_clock_moves(self):
        stamps = []
        self.node.create_subscription(
            Clock, '/clock', lambda msg: stamps.append(seconds_of(msg.clock)), 10)
        self.assertTrue(self.spin_until(lambda: len(stamps) > 1 and stamps[-1] > stamps[0],
                                        START_UP_TIMEOUT), stamps)

    def test_get_model_list_answers_with_tinybot(self):
        response = self.call(GetModelList, '/mujoco/get_model_list', GetModelList.Request())
        self.assertTrue(response.success)
        self.assertEqual(list(response.model_names), ['tinybot'])

    def test_the_turning_server_carries_out_a_turn(self):
        request = ControlTurningMessage.Request(time_duration=1, angular_vel=0.5)
        self.assertTrue(self.call(ControlTurningMessage, '/control_robot_angle', request).success)


@launch_testing.post_shutdown_test()
class TestAfterTheLaunch(unittest.TestCase):
    """What the processes left behind once launch_testing stopped them."""

    def test_every_process_ended_cleanly(self, proc_info):
        launch_testing.asserts.assertExitCodes(proc_info)
