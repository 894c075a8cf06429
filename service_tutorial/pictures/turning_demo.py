"""
The lesson from start to finish against a headless MuJoCo world: what scripts/demo runs.

It starts mujoco_world, robot_turning_server and robot_turning_action_server (on the world's
simulation time) as child processes, then walks through the lesson's services one step at a
time, printing what each did: spawn R2-D2, turn tinybot through /control_robot_angle and
measure how far it really turned, turn it again through the turn_robot action and cancel a
second action turn half way, delete R2-D2, reset the simulation. The children are stopped at
the end whatever happened; the exit status is 0 only if every step succeeded. With --web the
world serves its web page instead: the demo prints the page's address and keeps the world and
the turning servers running until Ctrl-C, for the lesson's steps to be clicked on the page.
"""

import argparse
import ctypes
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time

from action_msgs.msg import GoalStatus
from ament_index_python.packages import get_package_prefix, PackageNotFoundError
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from service_tutorial.conversions import seconds_of, yaw_of
from service_tutorial.lesson import model_services
from service_tutorial.lesson.goal_client import GoalClient
from service_tutorial.lesson.model_services import response_text
from service_tutorial.lesson.r2d2 import spawn_pose
from service_tutorial.node_main import program_arguments
from service_tutorial.pictures.recording import TurnRecorder
from srv_interfaces.action import TurnRobot
from srv_interfaces.srv import ControlTurningMessage, DeleteModel, GetModelState, SpawnModel
from std_srvs.srv import Empty

# How the demo prints an action's final status, as the action client does.
STATUS_NAMES = {getattr(GoalStatus, name): name[len('STATUS_'):]
                for name in dir(GoalStatus) if name.startswith('STATUS_')}

PACKAGE = 'service_tutorial'
ROBOT = 'tinybot'
# The nodes the demo needs, as (executable, ROS arguments). The world is the source of
# simulation time (it publishes /clock); the turning server follows it.
CHILDREN = (
    ('mujoco_world', ['-p', 'gui:=false', '-p', 'use_sim_time:=true']),
    ('robot_turning_server', ['-p', 'use_sim_time:=true']),
    ('robot_turning_action_server', ['-p', 'use_sim_time:=true']),
)
SERVICES = (
    (SpawnModel, model_services.SPAWN_MODEL_SERVICE),
    (DeleteModel, model_services.DELETE_MODEL_SERVICE),
    (Empty, model_services.RESET_SIMULATION_SERVICE),
    (GetModelState, model_services.GET_MODEL_STATE_SERVICE),
    (ControlTurningMessage, 'control_robot_angle'),
)
# With --record: the world's camera, 10 frames per simulated second (see config/world.yaml).
RECORD_CAMERA_ARGS = ['-p', 'camera_enabled:=true', '-p', 'camera_rate:=10.0',
                      '-p', 'camera_width:=480', '-p', 'camera_height:=360']
# How often tinybot's heading is sampled during a turn, in s: often enough to unwrap it.
HEADING_SAMPLE_PERIOD = 0.1
# Below this turning rate, in rad/s, tinybot counts as stopped.
AT_REST = 1e-3
# What the world logs before its web page's address.
WEB_PAGE_LOG = 'web page: '
# Seconds a child gets to stop after SIGINT before it is killed.
STOP_TIMEOUT = 5.0
# The action steps: a quarter turn left, and a half turn canceled half way, in rad and rad/s.
ACTION_TURN = (math.pi / 2, 0.5)
CANCELED_TURN = (math.pi, 0.5)


class DemoError(RuntimeError):
    """A step of the demo failed; the message says which and why."""


def say(text=''):
    """Print a line of the demo's story at once, even when stdout is a pipe."""
    print(text, flush=True)


def _stop_with_parent():
    """Have Linux send SIGTERM to this child if the demo dies without stopping it."""
    pr_set_pdeathsig = 1
    ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGTERM)


class Child:
    """A node run as a child process, its output going to a log file of its own."""

    def __init__(self, executable, ros_args, log_dir):
        self.name = executable
        self.log_path = os.path.join(log_dir, executable + '.log')
        command = executable_command(executable) + ['--ros-args'] + ros_args
        with open(self.log_path, 'w') as log_file:
            self.process = subprocess.Popen(
                command, stdin=subprocess.DEVNULL, stdout=log_file, stderr=subprocess.STDOUT,
                preexec_fn=_stop_with_parent if sys.platform.startswith('linux') else None)

    def check_running(self):
        """Raise DemoError, with the end of the child's log, if the child has exited."""
        status = self.process.poll()
        if status is not None:
            with open(self.log_path) as log_file:
                tail = ''.join(log_file.readlines()[-15:])
            raise DemoError(f'{self.name} exited with status {status}; the end of '
                            f'{self.log_path}:\n{tail}')

    def stop(self):
        """Stop the child as Ctrl-C would, and kill it if it does not stop in time."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(STOP_TIMEOUT)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
                return f'{self.name} killed (it ignored SIGINT for {STOP_TIMEOUT} s)'
        return f'{self.name} stopped (exit status {self.process.returncode})'


def executable_command(executable):
    """Return the command that runs one of this package's executables."""
    try:
        path = os.path.join(get_package_prefix(PACKAGE), 'lib', PACKAGE, executable)
    except PackageNotFoundError:
        path = None
    if path is not None and os.access(path, os.X_OK):
        return [path]
    return [sys.executable, '-m', f'{PACKAGE}.{executable}']


def wait_for_services(node, children, timeout):
    """Wait until every service the demo uses is up; fail early if a child exits."""
    clients = [node.create_client(srv_type, name) for srv_type, name in SERVICES]
    deadline = time.monotonic() + timeout
    try:
        while True:
            missing = [client.service_name for client in clients
                       if not client.service_is_ready()]
            if not missing:
                return
            for child in children:
                child.check_running()
            if time.monotonic() > deadline:
                raise DemoError(f'after {timeout} s still no {", ".join(missing)}')
            time.sleep(0.1)
    finally:
        for client in clients:
            node.destroy_client(client)


def robot_state(node, state_client, model_name=ROBOT):
    """Return a model's state in the world, from /mujoco/get_model_state (ground truth)."""
    request = GetModelState.Request()
    request.model_name = model_name
    state = model_services.call(node, state_client, request)
    if not state.success:
        raise DemoError(f'cannot read the state of {model_name}: {state.status_message}')
    return state


def spawn_r2d2(node):
    """Spawn R2-D2 the lesson's way and show where it landed."""
    response = model_services.spawn_model(
        node, 'r2d2', model_file=model_services.model_path('r2d2.urdf'),
        pose=spawn_pose(),
        reference_frame='world')
    say(indent(response_text(response)))
    if not response.success:
        raise DemoError(f'R2-D2 was not spawned: {response.status_message}')
    state = model_services.get_model_state(node, 'r2d2')
    position = state.pose.position
    say(indent(f'r2d2 is at x {position.x:.2f} m, y {position.y:.2f} m, z {position.z:.2f} m, '
               f'heading {math.degrees(yaw_of(state.pose.orientation)):.1f} deg'))


class HeadingFollower:
    """How far tinybot has turned since this was made, by ground truth sampled as it turns."""

    def __init__(self, node):
        self.node = node
        self.state_client = node.create_client(
            GetModelState, model_services.GET_MODEL_STATE_SERVICE)
        self.last = yaw_of(robot_state(node, self.state_client).pose.orientation)
        self.turned = 0.0

    def follow(self, event, timeout, what, *, until_at_rest=True):
        """Sample the heading until event is set (and tinybot has stopped); return the turn."""
        deadline = time.monotonic() + timeout
        # Sum the heading's changes: a heading alone is only known modulo 2 pi, a sum of
        # small changes is not.
        while True:
            event.wait(HEADING_SAMPLE_PERIOD)
            state = robot_state(self.node, self.state_client)
            heading = yaw_of(state.pose.orientation)
            self.turned += math.remainder(heading - self.last, math.tau)
            self.last = heading
            if event.is_set() and (not until_at_rest or abs(state.twist.angular.z) < AT_REST):
                return self.turned
            if time.monotonic() > deadline:
                raise DemoError(f'waited {timeout:.0f} s in vain for {what}')

    def destroy(self):
        """Let go of the state service's client."""
        self.node.destroy_client(self.state_client)


def turn_robot(node, time_duration, angular_vel):
    """Ask /control_robot_angle for a turn and measure how far tinybot really turned."""
    turning_client = node.create_client(ControlTurningMessage, 'control_robot_angle')
    heading = HeadingFollower(node)
    try:
        request = ControlTurningMessage.Request()
        request.time_duration = time_duration
        request.angular_vel = angular_vel
        future = turning_client.call_async(request)
        answered = threading.Event()
        future.add_done_callback(lambda _: answered.set())
        turned = heading.follow(answered, time_duration + 10.0, f'an answer from '
                                f'{turning_client.service_name} and tinybot at rest')
    finally:
        node.destroy_client(turning_client)
        heading.destroy()
    response = future.result()
    say(indent(response_text(response)))
    if not response.success:
        raise DemoError('the turning server refused the request or cut the turn short '
                        '(its log says why)')
    commanded = time_duration * angular_vel
    error = '' if commanded == 0.0 else f', {100.0 * (turned - commanded) / commanded:+.1f} %'
    say(indent(f'commanded {commanded:.3f} rad, tinybot turned {turned:.3f} rad{error}'))
    return turned


def send_turn_goal(node, angle, angular_vel, *, cancel_at=None):
    """
    Turn tinybot through the turn_robot action and measure how far it really turned.

    With cancel_at, the goal is canceled once the feedback says it has turned that far.
    Return the goal's final status, its result, the feedback and the ground truth turn.
    """
    turning_client = GoalClient(node, TurnRobot, 'turn_robot')
    heading = HeadingFollower(node)
    feedback = []
    reached = threading.Event()

    def feedback_callback(feedback_msg):
        feedback.append(feedback_msg.feedback)
        if cancel_at is not None and abs(feedback_msg.feedback.angle_turned) >= cancel_at:
            reached.set()

    timeout = abs(angle) / angular_vel + 10.0
    try:
        if not turning_client.wait_for_server(timeout_sec=10.0):
            raise DemoError('the turn_robot action server did not appear within 10 s')
        goal_future = turning_client.send_goal_async(
            TurnRobot.Goal(angle=angle, angular_vel=angular_vel),
            feedback_callback=feedback_callback)
        if not model_services.wait_for_future(node, goal_future, timeout=10.0):
            raise DemoError('turn_robot did not answer the goal within 10 s')
        goal_handle = goal_future.result()
        if not goal_handle.accepted:
            raise DemoError('the turning action server rejected the goal (its log says why)')
        result_future = goal_handle.get_result_async()
        ended = threading.Event()
        result_future.add_done_callback(lambda _: ended.set())
        if cancel_at is not None:
            heading.follow(reached, timeout, f'feedback of {cancel_at:.3f} rad turned',
                           until_at_rest=False)
            goal_handle.cancel_goal_async()
        turned = heading.follow(ended, timeout, 'the result of turn_robot and tinybot at rest')
    finally:
        turning_client.destroy()
        heading.destroy()
    response = result_future.result()
    say(indent(f'status: {STATUS_NAMES.get(response.status, response.status)}\n'
               f'{response_text(response.result)}'))
    return response.status, response.result, feedback, turned


def turn_by_action(node, angle, angular_vel):
    """Turn tinybot by an angle through the action and compare with ground truth."""
    _, result, feedback, turned = send_turn_goal(node, angle, angular_vel)
    say(indent(f'{len(feedback)} feedback messages; asked for {angle:.3f} rad, tinybot turned '
               f'{turned:.3f} rad, {100.0 * (turned - angle) / angle:+.1f} %'))
    if not result.success:
        raise DemoError(f'the turn by the action failed: {result.message}')


def cancel_half_way(node, angle, angular_vel):
    """Start a turn through the action, cancel it half way and show what was turned."""
    half_way = abs(angle) / 2
    status, result, feedback, turned = send_turn_goal(
        node, angle, angular_vel, cancel_at=half_way)
    canceled_at = next(report.angle_turned for report in feedback
                       if abs(report.angle_turned) >= half_way)
    say(indent(f'canceled at {canceled_at:.3f} rad by the feedback; the result says '
               f'{result.angle_turned:.3f} rad, tinybot turned {turned:.3f} rad'))
    if status != GoalStatus.STATUS_CANCELED:
        raise DemoError(f'the turn was not canceled: {result.message}')


def delete_r2d2(node):
    """Delete R2-D2, as `rosservice call /gazebo/delete_model` did in the lesson."""
    response = model_services.delete_model(node, 'r2d2')
    say(indent(response_text(response)))
    if not response.success:
        raise DemoError(f'R2-D2 was not deleted: {response.status_message}')


def reset(node):
    """Reset the simulation and show tinybot back at its start heading."""
    model_services.reset_simulation(node)
    state = model_services.get_model_state(node, ROBOT)
    say(indent(f'simulation time {seconds_of(state.header.stamp):.2f} s, '
               f'tinybot heading {yaw_of(state.pose.orientation):.3f} rad'))


def lesson_steps(options, node):
    """Return the demo's steps in order, as (title, function taking the demo's node)."""
    duration, velocity = options.duration, options.velocity
    steps = [
        ("spawn R2-D2 the lesson's way: /mujoco/spawn_urdf_model", spawn_r2d2),
        (f'turn tinybot: /control_robot_angle, {duration} s at {velocity} rad/s',
         lambda node: turn_robot(node, duration, velocity)),
        (f'turn tinybot by the action: turn_robot, {ACTION_TURN[0]:.3f} rad at up to '
         f'{ACTION_TURN[1]} rad/s', lambda node: turn_by_action(node, *ACTION_TURN)),
        (f'cancel a turn half way: turn_robot, {CANCELED_TURN[0]:.3f} rad at up to '
         f'{CANCELED_TURN[1]} rad/s', lambda node: cancel_half_way(node, *CANCELED_TURN)),
        ('delete R2-D2: /mujoco/delete_model', delete_r2d2),
        ('reset the simulation: /mujoco/reset_simulation', reset),
    ]
    if options.record:
        # Film from before R2-D2 appears until tinybot has turned, then save.
        recorder = TurnRecorder(node)
        if not recorder.wait_for_frame(options.startup_timeout):
            raise DemoError('--record: no image from /mujoco/camera/image_raw')
        steps.insert(2, (f'save the recording into {options.record}',
                         lambda node: save_recording(recorder, options.record)))
    return steps


def run_lesson(node, steps, children):
    """Run the steps one after the other, printing each as it starts."""
    for number, (title, step) in enumerate(steps, start=1):
        for child in children:
            child.check_running()
        say(f'[{number}/{len(steps)}] {title}')
        step(node)


def save_recording(recorder, directory):
    """Stop recording, write turning.gif and trajectory.svg into directory, print their paths."""
    paths = recorder.save(directory)
    if not paths:
        raise DemoError('nothing was recorded: no camera image and no odometry arrived')
    for path in paths:
        say(indent(f'wrote {os.path.abspath(path)}'))


def serve_page(world, timeout):
    """
    Print the address of the world's web page and keep everything running until Ctrl-C.

    The world logs the address once its page is up (viser takes the next port if the one asked
    for is taken), so it is read from the world's log.
    """
    deadline = time.monotonic() + timeout
    address = None
    while address is None:
        world.check_running()
        with open(world.log_path) as log_file:
            address = next((line.split(WEB_PAGE_LOG, 1)[1].split()[0] for line in log_file
                            if WEB_PAGE_LOG in line), None)
        if address is None:
            if time.monotonic() > deadline:
                raise DemoError(f'the world named no web page within {timeout} s')
            time.sleep(0.1)
    say(f"the world's web page: {address}")
    say(indent('open it in a browser on this machine: spawn R2-D2, turn and drive tinybot '
               'from its panel\nCtrl-C stops the world and the turning servers'))
    try:
        while True:
            world.check_running()
            time.sleep(0.5)
    except KeyboardInterrupt:
        say('turning_demo: stopping')


def indent(text):
    """Indent every line of a step's output under its title."""
    return '\n'.join('      ' + line for line in text.splitlines())


def parse_arguments(argv):
    """Read the command line (ROS arguments already removed)."""
    parser = argparse.ArgumentParser(
        prog='turning_demo',
        description='Run the MuJoCo world and the turning server, then walk through the '
                    "lesson's services step by step.")
    parser.add_argument('--duration', type=int, default=2,
                        help='turning time in whole seconds (default: %(default)s)')
    parser.add_argument('--velocity', type=float, default=0.5,
                        help='turning rate in rad/s (default: %(default)s)')
    parser.add_argument('--log-dir',
                        help="folder for the children's logs (default: a new temporary one)")
    parser.add_argument('--startup-timeout', type=float, default=30.0,
                        help='seconds to wait for the services (default: %(default)s)')
    parser.add_argument('--record', metavar='DIR',
                        help="film R2-D2 falling and tinybot turning with the world's camera; "
                             'write DIR/turning.gif and DIR/trajectory.svg')
    parser.add_argument('--web', action='store_true',
                        help="start the world with its web page, print the page's address and "
                             'keep running until Ctrl-C instead of walking the lesson')
    parser.add_argument('--web-port', type=int, default=8080,
                        help='port of the web page (default: %(default)s; the next free one if '
                             'taken)')
    options = parser.parse_args(argv)
    if options.duration < 0:
        parser.error(f'--duration must be 0 or more, got {options.duration}')
    return options


def main(args=None):
    """Run the demo; exit status 0 if every step succeeded."""
    options = parse_arguments(program_arguments(args))
    log_dir = options.log_dir or tempfile.mkdtemp(prefix='turning_demo-')
    os.makedirs(log_dir, exist_ok=True)
    # Ctrl-C and SIGTERM raise KeyboardInterrupt here, so the children are always stopped.
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    children = []
    node = executor = None
    status = 1
    try:
        for executable, ros_args in CHILDREN:
            if options.record and executable == 'mujoco_world':
                ros_args = ros_args + RECORD_CAMERA_ARGS
            if options.web and executable == 'mujoco_world':
                ros_args = ros_args + ['-p', 'web:=true', '-p', f'web_port:={options.web_port}']
            children.append(Child(executable, ros_args, log_dir))
        say(f'started {", ".join(f"{c.name} (pid {c.process.pid})" for c in children)}; '
            f'their logs are in {log_dir}')
        # The demo's node spins in a thread of its own while the steps below wait for answers.
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
        node = Node('turning_demo')
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        threading.Thread(target=executor.spin, daemon=True).start()
        started = time.monotonic()
        wait_for_services(node, children, options.startup_timeout)
        say(f'services up after {time.monotonic() - started:.1f} s')
        if options.web:
            serve_page(children[0], options.startup_timeout)
        else:
            run_lesson(node, lesson_steps(options, node), children)
        status = 0
    except (DemoError, TimeoutError) as error:
        print(f'turning_demo: failed: {error}', file=sys.stderr, flush=True)
    except KeyboardInterrupt:
        say('turning_demo: interrupted')
    finally:
        if executor is not None:
            # Bounded: the children are stopped below whatever the middleware does meanwhile.
            executor.shutdown(timeout_sec=STOP_TIMEOUT)
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
        for child in reversed(children):
            say(child.stop())
    say('done' if status == 0 else f'turning_demo: exit status {status}')
    return status


if __name__ == '__main__':
    sys.exit(main())
