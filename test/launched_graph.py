"""The test side of a launch_testing file: a node of its own beside what the launch runs."""

import time
import unittest

import rclpy
from rclpy.executors import SingleThreadedExecutor


class LaunchedGraphTestCase(unittest.TestCase):
    """Tests that meet the launched processes on the graph, through self.node."""

    node_name = 'launch_test'

    @classmethod
    def setUpClass(cls):
        """Make the node, on a context of its own (other tests may hold rclpy's default)."""
        cls.context = rclpy.Context()
        rclpy.init(context=cls.context)
        cls.node = rclpy.create_node(cls.node_name, context=cls.context)
        cls.executor = SingleThreadedExecutor(context=cls.context)
        cls.executor.add_node(cls.node)

    @classmethod
    def tearDownClass(cls):
        """Let the node and its context go."""
        cls.executor.shutdown()
        cls.node.destroy_node()
        rclpy.try_shutdown(context=cls.context)

    def spin_until(self, predicate, timeout):
        """Handle the node's work until predicate() holds or timeout s of wall time pass."""
        deadline = time.monotonic() + timeout
        while not predicate() and time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.1)
        return predicate()
