"""Start-up: from starting mujoco_world until every one of its services answers."""

import statistics
import subprocess
import sys
import time

from harness import BenchmarkError, NodeProcess, wait_until_gone
from report import Table

WORLD_SERVICES = ('spawn_urdf_model', 'delete_model', 'reset_simulation', 'reset_world',
                  'pause_physics', 'unpause_physics', 'get_model_list', 'get_model_state',
                  'set_model_state')


def world_services():
    """Return (type, name) of every /mujoco/ service start-up waits for."""
    from srv_interfaces.srv import DeleteModel, GetModelList, GetModelState, SetModelState
    from srv_interfaces.srv import SpawnModel
    from std_srvs.srv import Empty
    types = {'spawn_urdf_model': SpawnModel, 'delete_model': DeleteModel,
             'get_model_list': GetModelList, 'get_model_state': GetModelState,
             'set_model_state': SetModelState}
    return [(types.get(name, Empty), '/mujoco/' + name) for name in WORLD_SERVICES]


def startup_table(observer, config):
    """Process start of mujoco_world until every /mujoco/ service answers."""
    from srv_interfaces.srv import GetModelList
    services = world_services()
    for srv_type, name in services:
        observer.client(srv_type, name)  # discovery starts before the process does
    times, cpu_times = [], []
    for _ in range(config.startup_runs):
        wait_until_gone(observer, GetModelList, '/mujoco/get_model_list')
        start = time.monotonic()
        with NodeProcess('mujoco_world') as process:
            for srv_type, name in services:
                observer.wait_for_service(srv_type, name, process=process)
            response = observer.call(GetModelList, '/mujoco/get_model_list',
                                     GetModelList.Request())
            times.append(time.monotonic() - start)
            cpu_times.append(process.cpu_time())
            if list(response.model_names) != ['tinybot']:
                raise BenchmarkError(f'unexpected start-up models {response.model_names}')
    wait_until_gone(observer, GetModelList, '/mujoco/get_model_list')
    node_imports, urdf_imports = [], []
    for _ in range(max(1, min(3, config.startup_runs))):
        node_imports.append(_import_time('service_tutorial.world_node.node'))
        urdf_imports.append(_import_time('yourdfpy'))
    table = Table('startup', 'Start-up: mujoco_world process start to every /mujoco/ service '
                  'answering (s)', [
                      ('runs', 'd'), ('p50', '.3f'), ('max', '.3f'), ('CPU s p50', '.3f'),
                      ('node imports p50', '.3f'), ('yourdfpy import p50', '.3f'),
                      ('target', '.1f'), ('within', '')])
    p50 = statistics.median(times)
    table.rows.append([len(times), p50, max(times), statistics.median(cpu_times),
                       statistics.median(node_imports), statistics.median(urdf_imports), 1.5,
                       p50 < 1.5])
    table.note = ('CPU s: CPU time the world process had used when ready; node imports: wall '
                  'time of a fresh interpreter importing service_tutorial.world_node.node '
                  '(rclpy, MuJoCo, the messages); yourdfpy import: the same for yourdfpy, '
                  'which brings trimesh (and whatever of its extras is installed: scripts/setup '
                  'leaves them out), and which the world imports when it reads '
                  "its first URDF (the start-up world's); both are parts of any start-up")
    return table


def _import_time(module):
    """Return the wall time a fresh interpreter takes to start and import module, in s."""
    start = time.monotonic()
    subprocess.run([sys.executable, '-c', f'import {module}'], check=True)
    return time.monotonic() - start
