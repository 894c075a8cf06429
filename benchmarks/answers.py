"""Answers that need no simulation: model_services with no world, the turning server."""

import time

from harness import BenchmarkError, ExecutorThread, quiet_console, wait_until_gone
from report import Table


def answers_table(observer, config):
    """Time how soon a missing service is reported and a turn without turning answered."""
    from rclpy.node import Node
    from service_tutorial.lesson.model_services import delete_model, ServiceUnavailableError
    from service_tutorial.lesson.robot_turning_server import RobotTurningServer
    from srv_interfaces.srv import ControlTurningMessage
    table = Table('answers', 'Answers that need no simulation (s)', [
        ('call', ''), ('took', '.3f'), ('limit', '.1f'), ('within', '')])
    script = Node('benchmark_script', namespace='/nowhere')  # no world in this namespace
    try:
        start = time.monotonic()
        try:
            delete_model(script, 'r2d2', timeout=0.5)
            raise BenchmarkError('delete_model found a world under /nowhere')
        except ServiceUnavailableError:
            took = time.monotonic() - start
    finally:
        script.destroy_node()
    table.rows.append(['model_services.delete_model, no world, timeout 0.5 s', took, 1.5,
                       took < 1.5])
    with quiet_console(config.log_path):
        server = RobotTurningServer()
        executor_thread = ExecutorThread(server)
        try:
            observer.wait_for_service(ControlTurningMessage, '/control_robot_angle')
            for what, duration, velocity, success in (
                    ('refused: 1 s at 1.6 rad/s', 1, 1.6, False),
                    ('zero-length turn', 0, 1.0, True)):
                start = time.monotonic()
                response = observer.call(ControlTurningMessage, '/control_robot_angle',
                                         ControlTurningMessage.Request(
                                             time_duration=duration, angular_vel=velocity))
                took = time.monotonic() - start
                if response.success != success:
                    raise BenchmarkError(f'/control_robot_angle {what}: success '
                                         f'{response.success}')
                table.rows.append([f'/control_robot_angle, {what}', took, 2.0, took < 2.0])
        finally:
            executor_thread.stop()
            server.destroy_node()
    wait_until_gone(observer, ControlTurningMessage, '/control_robot_angle')
    table.note = ('the turning server in this process, on an executor thread of its own; '
                  'neither answer waits for a turn')
    return table
