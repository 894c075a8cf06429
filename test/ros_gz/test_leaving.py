"""
A program stops on Ctrl-C, and ends with its own status even when its middleware hangs.

Fast DDS 2.14 can spin for ever destroying a participant; a parameter_bridge that never ends
would keep its mappings in the world and a launch file from finishing. node_main's programs
give the middleware LEAVING_TIME, then end anyway. A server's Ctrl-C is a flag it looks at,
not a KeyboardInterrupt that code in its way may drop.
"""

import contextlib
import signal
import subprocess
import sys
import textwrap

from service_tutorial.node_main import LEAVING_TIME


@contextlib.contextmanager
def started(program, first_line):
    """Run a test program; yield it once it has printed first_line, kill it after."""
    process = subprocess.Popen([sys.executable, '-c', program], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    try:
        assert process.stdout.readline() == first_line
        yield process
    finally:
        process.kill()
        process.communicate()


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


# A server that takes a while to let its node go, and says when it starts and ends.
SLOW_TO_LEAVE_SERVER = textwrap.dedent("""
    import sys
    import time

    from rclpy.node import Node
    from service_tutorial.node_main import spin_node


    class SlowToLeave(Node):
        def __init__(self):
            super().__init__('slow_to_leave')
            self.timer = self.create_timer(0.01, self.say_spinning)

        def say_spinning(self):
            print('spinning', flush=True)
            self.timer.cancel()

        def destroy_node(self):
            print('leaving', flush=True)
            time.sleep(1.0)
            super().destroy_node()
            print('left', flush=True)


    sys.exit(spin_node(SlowToLeave, args=['slow_to_leave']))
""")


def test_a_second_ctrl_c_while_a_server_leaves_lets_it_finish_leaving():
    with started(SLOW_TO_LEAVE_SERVER, 'spinning\n') as server:
        server.send_signal(signal.SIGINT)
        assert server.stdout.readline() == 'leaving\n'
        server.send_signal(signal.SIGINT)  # an impatient user
        out, err = server.communicate(timeout=LEAVING_TIME)
    assert out == 'left\n' and server.returncode == 0, err
    assert 'Traceback' not in err, err


# A server whose timer callback blocks for ten minutes, as one that waits on a socket might.
BLOCKED_SERVER = textwrap.dedent("""
    import sys
    import time

    from rclpy.node import Node
    from service_tutorial.node_main import spin_node


    class Blocked(Node):
        def __init__(self):
            super().__init__('blocked')
            self.timer = self.create_timer(0.01, self.block)

        def block(self):
            self.timer.cancel()
            print('blocking', flush=True)
            time.sleep(600.0)


    sys.exit(spin_node(Blocked, args=['blocked']))
""")


def test_ctrl_c_ends_a_server_whose_spinning_is_held_up():
    with started(BLOCKED_SERVER, 'blocking\n') as server:
        server.send_signal(signal.SIGINT)
        # The spinning is given LEAVING_TIME to end, the middleware as long to let go.
        out, err = server.communicate(timeout=2 * LEAVING_TIME + 30.0)
    assert server.returncode == 0, err
    assert 'Traceback' not in err, err
