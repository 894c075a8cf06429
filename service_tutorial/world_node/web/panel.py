"""
The page's panel: the lesson's buttons, the turn's fields, the drive buttons, the sensors, status.

Every button goes through PageClient, so the page asks the world exactly what a ROS client
would and gets the same answers, shown under "Answer". The turn's fields are read as the
lesson's robot_turning_client reads what is typed, with its limits and its refusals
(service_tutorial.turning_input), before anything is sent. The status (simulation time,
real-time factor, models) is set by the world's thread, a few times a second while someone
watches; so are the sensors' choices offered and their pictures (sensor_view.py).
"""

import threading

import numpy as np

from service_tutorial.turning_input import parse_turning_request, TurningInputError
from std_srvs.srv import Empty

# Drive buttons: label, linear (m/s) and angular (rad/s) velocity, as a teleop's keys give.
DRIVE_BUTTONS = (('Forward', 0.2, 0.0), ('Left', 0.0, 0.5), ('Stop', 0.0, 0.0),
                 ('Right', 0.0, -0.5), ('Back', -0.2, 0.0))
DROPPED = 'still waiting for the last answer: click dropped'
NO_SERVICE = '{service} is not there'
NO_TURNING_SERVER = ' (start it: robot_turning_server --ros-args -p use_sim_time:=true)'
NO_CAMERA = 'none'


class Panel:
    """The page's controls and status, in viser's GUI."""

    def __init__(self, gui, client, r2d2_urdf):
        """Lay out the panel on gui; its buttons call client; r2d2_urdf is what spawn sends."""
        self.client = client
        self.r2d2_urdf = r2d2_urdf
        self._status_lock = threading.Lock()
        self._answer_lock = threading.Lock()
        self.answers = 0  # answers shown so far
        self.status = gui.add_markdown('**Simulation time** -')
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
        with gui.add_folder('Sensors'):
            self.show_lasers = gui.add_checkbox('Show lasers', False)
            self.camera_choice = gui.add_dropdown('Camera', (NO_CAMERA,))
            self.camera_image = gui.add_image(np.zeros((2, 2, 3), dtype=np.uint8),
                                              format='jpeg', visible=False)
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

    def offer_cameras(self, image_topics):
        """Offer the robots' cameras by image topic; a choice that went falls back to none."""
        chosen = self.camera_choice.value
        self.camera_choice.options = (NO_CAMERA, *image_topics)
        if chosen not in image_topics:
            self.camera_choice.value = NO_CAMERA

    def show_status(self, sim_time, real_time_factor, model_names, paused):
        """Show simulation time, real-time factor and the models (from the world's thread)."""
        factor = '-' if real_time_factor is None else f'{real_time_factor:.2f}'
        text = (f'**Simulation time** {sim_time:.2f} s{" (paused)" if paused else ""}  \n'
                f'**Real-time factor** {factor}  \n'
                f'**Models** {", ".join(model_names) or "none"}')
        with self._status_lock:
            if self.status.content != text:
                self.status.content = text
