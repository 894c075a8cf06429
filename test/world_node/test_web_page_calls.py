"""
The web page's panel and its ROS client, without a browser: what each click sends and says.

The buttons' callbacks are called as viser calls them, on a thread that is not the world's; the
answers come back through the page's own node. The browser tests (test_web_page.py) check the
same through real clicks; these check what a browser cannot make happen on purpose.
"""

import threading
import time

import pytest
from service_tutorial.lesson.turning_input import NOT_A_NUMBER
from service_tutorial.lesson.web_panel import DROPPED, NO_TURNING_SERVER
from service_tutorial.sim.plugins.camera_sensor import CameraSensor
from service_tutorial.sim.plugins.ray_sensor import RaySensor
from srv_interfaces.srv import GetModelList
from web_browser import free_port

pytestmark = pytest.mark.ros


@pytest.fixture
def page(ros):
    """Start the world with its page served, and no turning server; return the page."""
    world = ros.start_world(web=True, web_port=free_port())
    return world.node.web_page


class PageConnection:
    """One browser's websocket to the page, as viser's own client opens it; read or not."""

    def __init__(self, address, *, reads):
        import msgspec
        import viser
        from viser._messages import ViewerCameraMessage
        from websockets.sync.client import connect
        self.socket = connect(address.replace('http://', 'ws://'), max_size=None,
                              subprotocols=[f'viser-v{viser.__version__}'])
        # A page counts as connected once it has said where its camera looks, as viser's does.
        camera = ViewerCameraMessage(
            wxyz=(1.0, 0.0, 0.0, 0.0), position=(3.0, 3.0, 2.0), fov=1.0, near=0.01,
            far=100.0, image_height=600, image_width=800, look_at=(0.0, 0.0, 0.0),
            up_direction=(0.0, 0.0, 1.0))
        self.socket.send(msgspec.msgpack.encode(camera.as_serializable_dict()))
        self.received = 0  # bytes
        self.thread = None
        if reads:
            self.thread = threading.Thread(target=self._read, daemon=True)
            self.thread.start()

    def _read(self):
        try:
            for message in self.socket:
                self.received += len(message)
        except Exception:  # closed under it
            pass

    def close(self):
        self.socket.close()
        if self.thread is not None:
            self.thread.join(timeout=5.0)


def answer_to(ros, panel, click, *, timeout=10.0):
    """Click (call a button's callback) and wait for the answer line it brings; return it."""
    number = panel.answers + 1
    click()
    assert ros.wait_for(lambda: panel.answers >= number, timeout=timeout)
    return panel.answer.content


def test_a_second_spawn_click_while_the_first_is_unanswered_is_dropped_and_said(ros, page):
    panel, client = page.panel, page.client
    release = threading.Event()
    answered = []
    sent = client.spawn_r2d2(panel.r2d2_urdf, lambda response: (release.wait(10.0),
                                                                answered.append(response)))
    panel.spawn_clicked()  # the first call's answer is held back: this click comes too soon

    assert sent
    assert panel.answer.content.endswith(DROPPED)
    assert client.dropped_calls == 1
    release.set()
    assert ros.wait_for(lambda: answered, timeout=10.0)
    assert answered[0].success, answered[0].status_message
    # Once answered, the next click goes through and gets the world's own answer.
    assert "a model named 'r2d2' already exists" in answer_to(ros, panel, panel.spawn_clicked)


def test_a_turn_without_a_turning_server_says_which_service_is_missing(ros, page):
    panel = page.panel
    text = answer_to(ros, panel, panel.turn_clicked)

    assert '/control_robot_angle is not there' in text and NO_TURNING_SERVER in text


def test_a_bad_turn_is_refused_before_anything_is_sent(ros, page):
    panel, client = page.panel, page.client
    panel.velocity_text.value = '0.5rad'
    panel.turn_clicked()

    assert panel.answer.content.endswith(NOT_A_NUMBER)
    assert client.sent_calls == 0


def test_with_no_browser_the_world_steps_and_the_page_sends_nothing(ros, page):
    started = page.world.time
    assert ros.wait_for(lambda: page.world.time > started + 0.2, timeout=10.0)

    assert page.watchers == 0 and page.updates == 0 and page.scene.redraws == 0


def test_many_browsers_and_stalled_ones_neither_stop_the_world_nor_slow_its_answers(ros):
    world = ros.start_world(web=True, web_port=free_port())
    page = world.node.web_page
    laser = world.node.world.models['tinybot'].plugin(RaySensor)
    camera = world.node.world.models['tinybot'].plugin(CameraSensor)
    # Twelve pages at once, four of them never reading what the page sends them.
    connections = [PageConnection(page.address, reads=number % 3 != 0) for number in range(12)]
    try:
        assert ros.wait_for(lambda: page.watchers == 12, timeout=10.0)
        page.panel.show_lasers.value = True  # as a click on one of the pages sets it for all
        assert ros.wait_for(lambda: '/camera/image_raw' in page.panel.camera_choice.options,
                            timeout=10.0)
        page.panel.camera_choice.value = '/camera/image_raw'
        assert ros.wait_for(lambda: laser.active and camera.active, timeout=10.0)
        assert ros.wait_for(lambda: page.sensors.images_sent > 0, timeout=10.0)
        started, wall = world.now(), time.monotonic()
        slowest = 0.0
        for _ in range(40):
            asked = time.monotonic()
            world.call(GetModelList, 'get_model_list', GetModelList.Request(), timeout=2.0)
            slowest = max(slowest, time.monotonic() - asked)
        factor = (world.now() - started) / (time.monotonic() - wall)
        readers = [connection for connection in connections if connection.thread]
        assert all(connection.received > 0 for connection in readers)
        assert factor > 0.5, f'real-time factor {factor:.2f} with twelve pages'
        print(f'twelve pages, four stalled: 40 listings, slowest {slowest * 1000:.1f} ms; '
              f'real-time factor {factor:.2f}')
    finally:
        for connection in connections:
            connection.close()
    assert ros.wait_for(lambda: page.watchers == 0, timeout=10.0)
    assert ros.wait_for(lambda: not (laser.active or camera.active), timeout=5.0)
