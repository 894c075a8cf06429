"""
The lesson's panel on the world's web page: its buttons, the turn's fields, the drive buttons.

The world's page (world_node/web/) draws the world and its sensors and knows nothing of the
lesson; service_tutorial/lesson_world.py hands it this panel, which extends the page's Panel
with the lesson's controls, as a Gazebo plugin extends Gazebo's plugin classes. Every button
goes through the page's ROS client (LessonPageClient: the page's PageClient with the lesson's
calls), so the page asks the world exactly what a ROS client would and shows the answer,
numbered, under "Answer". The turn's fields are read as robot_turning_client reads what is
typed, with its limits and its refusals (turning_input.py), before anything is sent.
"""

import threading

from geometry_msgs.msg import Twist
from service_tutorial.lesson.model_services import model_path
from service_tutorial.lesson.r2d2 import R2D2_FILE, R2D2_NAME, spawn_pose
from service_tutorial.lesson.turning_input import parse_turning_request, TurningInputError
from service_tutorial.sim.robot_files import read_path
from service_tutorial.world_node.web.page_client import PageClient
from service_tutorial.world_node.web.panel import Panel
from srv_interfaces.srv import ControlTurningMessage, DeleteModel, SpawnModel
from std_srvs.srv import Empty

# Drive buttons: label, linear (m/s) and angular (rad/s) velocity, as a teleop's keys give.
DRIVE_BUTTONS = (('Forward', 0.2, 0.0), ('Left', 0.0, 0.5), ('Stop', 0.0, 0.0),
                 ('Right', 0.0, -0.5), ('Back', -0.2, 0.0))
# A drive button is a teleop's key held for this long: its Twist is sent again every period,
# so the world's cmd_vel_timeout does not stop the robot while the command stands.
DRIVE_HOLD = 1.0  # s
DRIVE_PERIOD = 0.1  # s
CMD_VEL_DEPTH = 10
DROPPED = 'still waiting for the last answer: click dropped'
NO_SERVICE = '{service} is not there'
NO_TURNING_SERVER = ' (start it: robot_turning_server --ros-args -p use_sim_time:=true)'


class LessonPageClient(PageClient):
    """The page's ROS client with the lesson's calls: R2-D2, the world's services, the turn."""

    def __init__(self, world_node):
        """Add the lesson's service clients and tinybot's cmd_vel to the page's node."""
        super().__init__(world_node)
        world = self.world_name
        for kind, srv_type, name in (
                ('spawn', SpawnModel, f'{world}/spawn_urdf_model'),
                ('delete', DeleteModel, f'{world}/delete_model'),
                ('reset', Empty, f'{world}/reset_simulation'),
                ('pause', Empty, f'{world}/pause_physics'),
                ('resume', Empty, f'{world}/unpause_physics'),
                ('turn', ControlTurningMessage, 'control_robot_angle')):
            self.add_call(kind, srv_type, name)
        # Relative: tinybot's cmd_vel in the world's namespace.
        self.cmd_vel_pub = self.node.create_publisher(Twist, 'cmd_vel', CMD_VEL_DEPTH)
        self._drive = Twist()
        self._drive_until = 0.0
        self.drive_timer = self.node.create_timer(DRIVE_PERIOD, self.drive_timer_callback)
        self.drive_timer.cancel()
        self._drive_lock = threading.Lock()

    def spawn_r2d2(self, urdf, answered):
        """Ask the world to spawn R2-D2 where the lesson does."""
        request = SpawnModel.Request(model_name=R2D2_NAME, model_xml=urdf,
                                     initial_pose=spawn_pose())
        return self.call('spawn', request, answered)

    def delete_r2d2(self, answered):
        """Ask the world to delete R2-D2."""
        return self.call('delete', DeleteModel.Request(model_name=R2D2_NAME), answered)

    def turn(self, time_duration, angular_vel, answered):
        """Ask /control_robot_angle for a turn already checked against the lesson's limits."""
        request = ControlTurningMessage.Request(time_duration=time_duration,
                                                angular_vel=angular_vel)
        return self.call('turn', request, answered)

    def drive(self, linear, angular):
        """Send a Twist on cmd_vel now and for DRIVE_HOLD seconds; (0, 0) stops at once."""
        twist = Twist()
        twist.linear.x, twist.angular.z = float(linear), float(angular)
        with self._drive_lock:
            self._drive = twist
            self._drive_until = self.node.get_clock().now().nanoseconds * 1e-9 + DRIVE_HOLD
        self.cmd_vel_pub.publish(twist)
        if linear or angular:
            self.drive_timer.reset()
        else:
            self.drive_timer.cancel()

    def drive_timer_callback(self):
        """Send the standing drive command again, until it has been held DRIVE_HOLD s."""
        with self._drive_lock:
            twist, until = self._drive, self._drive_until
        if self.node.get_clock().now().nanoseconds * 1e-9 >= until:
            self.drive_timer.cancel()
            return
        self.cmd_vel_pub.publish(twist)


class LessonPanel(Panel):
    """The lesson's buttons and the answers they get, on the world's page."""

    client_type = LessonPageClient

    def __init__(self, gui, client):
        """Lay out the page's panel with the lesson's controls; spawn sends R2-D2's URDF."""
        self.r2d2_urdf = read_path(model_path(R2D2_FILE), formats=('urdf',)).text
        self._answer_lock = threading.Lock()
        self.answers = 0  # answers shown so far
        super().__init__(gui, client)

    def add_controls(self, gui):
        """Add the lesson's buttons, the turn's fields, the drive buttons and the answer line."""
        client = self.client
        with gui.add_folder('The lesson'):
            self._button(gui, 'Spawn R2-D2', self.spawn_clicked)
            self._button(gui, 'Delete R2-D2', self.delete_clicked)
            self._button(gui, 'Reset simulation', self.reset_clicked)
            self._button(gui, 'Pause', lambda: self._empty_call('pause'))
            self._button(gui, 'Resume', lambda: self._empty_call('resume'))
        with gui.add_folder('Turn tinybot'):
            self.duration_text = gui.add_text('Time (s)', '2')
            self.velocity_text = gui.add_text('Velocity (rad/s)', '0.5')
            self._button(gui, 'Turn', self.turn_clicked)
        with gui.add_folder('Drive tinybot'):
            for label, linear, angular in DRIVE_BUTTONS:
                self._button(gui, label, lambda linear=linear, angular=angular:
                             client.drive(linear, angular))
        self.answer = gui.add_markdown('**Answer** -')

    @staticmethod
    def _button(gui, label, clicked):
        button = gui.add_button(label)
        button.on_click(lambda _event: clicked())
        return button

    def say(self, text):
        """Show an answer or a refusal under the buttons, numbered to tell it from the last."""
        with self._answer_lock:
            self.answers += 1
            self.answer.content = f'**Answer {self.answers}** {text}'

    def _sent_or_dropped(self, sent):
        if not sent:
            self.say(DROPPED)

    def _not_there(self, kind):
        return NO_SERVICE.format(service=self.client.service_name(kind))

    def spawn_clicked(self):
        """Spawn R2-D2 through the world's spawn service, where the lesson puts it."""
        self._sent_or_dropped(self.client.spawn_r2d2(self.r2d2_urdf,
                                                     self._model_answered('spawn')))

    def delete_clicked(self):
        """Delete R2-D2 through the world's delete service."""
        self._sent_or_dropped(self.client.delete_r2d2(self._model_answered('delete')))

    def _model_answered(self, kind):
        def answered(response):
            self.say(response.status_message if response is not None
                     else self._not_there(kind))
        return answered

    def reset_clicked(self):
        """Reset the simulation through the world's reset service."""
        self._empty_call('reset')

    def _empty_call(self, kind):
        def answered(response):
            self.say(f'{self.client.service_name(kind)}: done' if response is not None
                     else self._not_there(kind))
        self._sent_or_dropped(self.client.call(kind, Empty.Request(), answered))

    def turn_clicked(self):
        """Read the turn's fields as the lesson's client does; send the turn if they pass."""
        try:
            duration, velocity = parse_turning_request(self.duration_text.value,
                                                       self.velocity_text.value)
        except TurningInputError as error:
            self.say(str(error))  # the lesson client's own words
            return

        def answered(response):
            if response is None:
                self.say(self._not_there('turn') + NO_TURNING_SERVER)
            else:
                self.say(f'{self.client.service_name("turn")}: success {response.success} '
                         f'({duration} s at {velocity} rad/s)')
        self._sent_or_dropped(self.client.turn(duration, velocity, answered))
