"""The main job end to end: turning_demo starts the world and the server and walks the lesson."""

import os
import re
import signal
import subprocess

from ament_index_python.packages import get_package_prefix
import pytest

DEMO = os.path.join(get_package_prefix('service_tutorial'), 'lib', 'service_tutorial',
                    'turning_demo')

pytestmark = pytest.mark.ros


def run_demo(*args, log_dir):
    return subprocess.run([DEMO, '--log-dir', str(log_dir), *args], capture_output=True,
                          text=True, timeout=90)


def child_pids(output):
    return [int(pid) for pid in re.findall(r'\(pid (\d+)\)', output)]


def assert_gone(pids):
    for pid in pids:
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


def test_demo_walks_the_lesson_and_measures_the_turn(tmp_path):
    finished = run_demo(log_dir=tmp_path)

    assert finished.returncode == 0, finished.stdout + finished.stderr
    output = finished.stdout
    for step in ('[1/4] spawn R2-D2', '[2/4] turn tinybot', '[3/4] delete R2-D2',
                 '[4/4] reset the simulation'):
        assert step in output
    assert output.count('success: True') == 3
    turned = re.search(r'commanded 1\.000 rad, tinybot turned (-?\d+\.\d+) rad', output)
    assert turned, output
    # The turn's accuracy is the turning server tests' business; here it must be about right.
    assert float(turned.group(1)) == pytest.approx(1.0, rel=0.1)
    assert output.rstrip().endswith('done')
    assert (tmp_path / 'mujoco_world.log').stat().st_size > 0
    assert (tmp_path / 'robot_turning_server.log').stat().st_size > 0
    assert len(child_pids(output)) == 2
    assert_gone(child_pids(output))


def test_a_failing_step_stops_the_demo_with_a_clear_message(tmp_path):
    finished = run_demo('--velocity', '2.0', log_dir=tmp_path)

    assert finished.returncode == 1
    assert 'refused' in finished.stderr
    assert '[3/4]' not in finished.stdout
    assert 'faster than max_angular_vel' in (tmp_path / 'robot_turning_server.log').read_text()
    assert_gone(child_pids(finished.stdout))


def test_ctrl_c_mid_demo_stops_the_children(tmp_path):
    demo = subprocess.Popen([DEMO, '--log-dir', str(tmp_path)], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    try:
        seen = []
        for line in demo.stdout:
            seen.append(line)
            if line.startswith('[2/4]'):
                break
        demo.send_signal(signal.SIGINT)
        rest = demo.stdout.read()
        assert demo.wait(timeout=30) == 1
    finally:
        if demo.poll() is None:
            demo.kill()
            demo.wait()
        demo.stdout.close()

    assert 'interrupted' in rest
    assert 'mujoco_world stopped' in rest and 'robot_turning_server stopped' in rest
    assert_gone(child_pids(''.join(seen)))
