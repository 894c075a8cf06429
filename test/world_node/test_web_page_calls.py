"""
The web page's panel and its ROS client, without a browser: what each click sends and says.

The buttons' callbacks are called as viser calls them, on a thread that is not the world's; the
answers come back through the page's own node. The browser tests (test_web_page.py) check the
same through real clicks; these check what a browser cannot make happen on purpose.
"""

import threading

import pytest
from service_tutorial.turning_input import NOT_A_NUMBER
from service_tutorial.world_node.web.panel import DROPPED, NO_TURNING_SERVER
from web_browser import free_port

pytestmark = pytest.mark.ros


@pytest.fixture
def page(ros):
    """Start the world with its page served, and no turning server; return the page."""
    world = ros.start_world(web=True, web_port=free_port())
    return world.node.web_page


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
