"""
A program whose middleware hangs as it lets the node go still ends, with its own status.

Fast DDS 2.14 can spin for ever destroying a participant; a parameter_bridge that never ends
would keep its mappings in the world and a launch file from finishing. node_main's programs
give the middleware LEAVING_TIME, then end anyway.
"""

import subprocess
import sys
import textwrap

from service_tutorial.node_main import LEAVING_TIME

# A server (spin_node) that shuts rclpy down from its first timer, and hangs in destroy_node.
STUCK_SERVER = textwrap.dedent("""
    import sys
    import threading

    import rclpy
    from rclpy.node import Node
    from service_tutorial.node_main import spin_node


    class Stuck(Node):
        def __init__(self):
            super().__init__('stuck_in_leaving')
            self.create_timer(0.01, rclpy.try_shutdown)

        def destroy_node(self):
            print('leaving', flush=True)
            threading.Event().wait()


    sys.exit(spin_node(Stuck, args=['stuck']))
""")


def test_a_program_stuck_leaving_ends_after_the_leaving_time_with_status_0():
    done = subprocess.run([sys.executable, '-c', STUCK_SERVER], capture_output=True, text=True,
                          timeout=LEAVING_TIME + 60)
    assert done.stdout == 'leaving\n'
    assert done.returncode == 0, done.stderr
    assert (f'the middleware did not let the node go within {LEAVING_TIME:g} s; ending anyway'
            in done.stderr)
