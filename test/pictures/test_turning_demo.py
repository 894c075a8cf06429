"""The main job end to end: turning_demo starts the world and the server and walks the lesson."""

import math
import os
import re
import signal
import socket
import subprocess
import urllib.request

from programs import lines_of, program_path, run_program
import pytest

pytestmark = pytest.mark.ros


def run_demo(*args, log_dir):
    return run_program('turning_demo', '--log-dir', str(log_dir), *args, timeout=90)


def child_pids(output):
    return [int(pid) for pid in re.findall(r'\(pid (\d+)\)', output)]


def assert_gone(pids):
    for pid in pids:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


@pytest.mark.long
def test_demo_walks_the_lesson_and_measures_the_turn(tmp_path):
    finished = run_demo(log_dir=tmp_path)

    assert finished.returncode == 0, finished.stdout + finished.stderr
    output = finished.stdout
    for step in ('[1/6] spawn R2-D2', '[2/6] turn tinybot', '[3/6] turn tinybot by the action',
                 '[4/6] cancel a turn half way', '[5/6] delete R2-D2',
                 '[6/6] reset the simulation'):
        assert step in output
    assert output.count('success: True') == 4
    turned = re.search(r'commanded 1\.000 rad, tinybot turned (-?\d+\.\d+) rad', output)
    assert turned, output
    # The turn's accuracy is the turning server tests' business, on simulated time; here it
    # must be about right. The demo's world runs in real time, and a stop that a busy machine
    # delivers 0.2 s late turns tinybot a tenth too far (1.11 in a CI run on three workers).
    assert float(turned.group(1)) == pytest.approx(1.0, rel=0.25)
    by_action = re.search(r'asked for 1\.571 rad, tinybot turned (-?\d+\.\d+) rad', output)
    assert by_action, output
    assert float(by_action.group(1)) == pytest.approx(math.pi / 2, rel=0.05)
    assert 'status: SUCCEEDED' in output and 'status: CANCELED' in output
    canceled = re.search(r'canceled at (\d+\.\d+) rad by the feedback; the result says '
                         r'(\d+\.\d+) rad, tinybot turned (\d+\.\d+) rad', output)
    assert canceled, output
    at, reported, truth = (float(angle) for angle in canceled.groups())
    assert math.pi / 2 <= at <= reported < math.pi * 0.75
    assert reported == pytest.approx(truth, abs=0.02)
    assert output.rstrip().endswith('done')
    assert (tmp_path / 'mujoco_world.log').stat().st_size > 0
    assert (tmp_path / 'robot_turning_server.log').stat().st_size > 0
    assert (tmp_path / 'robot_turning_action_server.log').stat().st_size > 0
    assert len(child_pids(output)) == 3
    assert_gone(child_pids(output))


@pytest.mark.long
def test_a_failing_step_stops_the_demo_with_a_clear_message(tmp_path):
    finished = run_demo('--velocity', '2.0', log_dir=tmp_path)

    assert finished.returncode == 1
    assert 'refused' in finished.stderr
    assert '[3/6]' not in finished.stdout
    assert 'faster than max_angular_vel' in (tmp_path / 'robot_turning_server.log').read_text()
    assert_gone(child_pids(finished.stdout))


@pytest.mark.long
def test_ctrl_c_mid_demo_stops_the_children(tmp_path, start_program):
    demo = start_program([program_path('turning_demo'), '--log-dir', str(tmp_path)],
                         stderr=subprocess.STDOUT)
    seen = []
    for line in lines_of(demo):
        seen.append(line)
        if line.startswith('[2/6]'):
            break
    demo.send_signal(signal.SIGINT)
    rest = demo.stdout.read()
    assert demo.wait(timeout=30) == 1

    assert 'interrupted' in rest
    assert 'mujoco_world stopped' in rest and 'robot_turning_server stopped' in rest
    assert 'robot_turning_action_server stopped' in rest
    assert_gone(child_pids(''.join(seen)))


@pytest.mark.long
def test_web_prints_the_page_address_serves_it_and_ctrl_c_ends_it_cleanly(tmp_path,
                                                                          start_program):
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        port = probe.getsockname()[1]
    demo = start_program([program_path('turning_demo'), '--web', '--web-port', str(port),
                          '--log-dir', str(tmp_path)], stderr=subprocess.STDOUT)
    seen = []
    for line in lines_of(demo):
        seen.append(line)
        if "the world's web page: " in line:
            break
    address = seen[-1].split("the world's web page: ")[1].strip()
    with urllib.request.urlopen(address, timeout=10) as page:
        html = page.read().decode()
    demo.send_signal(signal.SIGINT)
    rest = demo.stdout.read()

    assert demo.wait(timeout=30) == 0, ''.join(seen) + rest
    assert address == f'http://127.0.0.1:{port}'
    assert '<html' in html
    assert 'mujoco_world stopped' in rest and rest.rstrip().endswith('done')
    assert_gone(child_pids(''.join(seen)))
