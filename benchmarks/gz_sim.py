"""
gz-sim's sensors and a TurtleBot3-style world of three Burgers, against their references.

The gz lidar and depth camera are timed against their raw MuJoCo cost, as the Classic sensors'
rows are (sensors.py). Three Burgers in an SDF world of walls and pillars (worlds/ beside this
file) are started as a TurtleBot3 launch starts them: mujoco_world with world:= the SDF file
and one create per robot at the same time, each Burger's SDF with its topics under its own name
(tb3_0/cmd_vel), as multi-robot TurtleBot3 setups give each robot its own. create gives it
with -string, since the world spawns files only from installed packages and the suite's
Burger is not installed. Their start-up, the world process's resident memory and the
real-time factor they reach free-running are printed beside what Robotnik's public simulator
benchmark (2025) measured for Gazebo Harmonic headless on another machine.
"""

import copy
import os
import statistics
import subprocess
import time

from harness import BenchmarkError, ClosedOnExit, NodeProcess, PACKAGE, sim_time_sample
from harness import wait_until, wait_until_gone, wait_until_world_gone
import mujoco
import numpy as np
from report import median_ms, Table
from sensors import ray_sensor_times
from service_tutorial.sim.rendering import MULTISAMPLED_PIXELS, release_gl_context
from service_tutorial.sim.rendering import SHADOW_SIZE
from service_tutorial.testing.spawns import spawn_robot
from startup import world_services

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SDF_MODELS = os.path.join(ROOT, 'test', 'models', 'sdf', 'models')
BURGER = os.path.join(SDF_MODELS, 'burger', 'model.sdf')
SURVEYOR = os.path.join(SDF_MODELS, 'surveyor', 'model.sdf')
ARENA = os.path.join(ROOT, 'benchmarks', 'worlds', 'burger_arena.sdf')
# A 16-row lidar (a VLP-16's 30 degrees) on the Burger's 360-beam rows.
VERTICAL_ROWS = ('<vertical><samples>16</samples><resolution>1</resolution>'
                 '<min_angle>-0.2618</min_angle><max_angle>0.2618</max_angle></vertical>')
DEPTH_SIZE = (320, 240)
# The Burgers, where they start in the arena, and what they are told on cmd_vel (m/s, rad/s).
BURGERS = {'tb3_0': (-0.6, -0.6), 'tb3_1': (0.6, -0.6), 'tb3_2': (0.0, 0.6)}
DRIVE = (0.2, 0.5)
# Robotnik's simulator benchmark (2025), Gazebo Harmonic headless, measured on their machine.
GAZEBO_STARTUP = 4.3        # s, one robot
GAZEBO_MEMORY = 1.45        # GB, one robot
GAZEBO_REAL_TIME = 0.66     # real-time factor, three robots
BURGER_TOPICS = ('cmd_vel', 'odom', 'joint_states', 'scan', 'imu')
SENSOR_LIMIT = 1.5          # the Classic sensors' limit: at most 1.5 x the raw MuJoCo cost


def sdf_text(path):
    """Return an SDF file's text."""
    with open(path) as sdf_file:
        return sdf_file.read()


def sensor_world(robot, text):
    """Return a ROS-free World in the yard holding one SDF robot, settled."""
    from fleet import model_path
    from service_tutorial.sim.world import World
    world = World(scenery=model_path('yard'))
    spawn_robot(world, robot, text, model_format='sdf', base_dir=os.path.dirname(BURGER))
    world.step(250)
    return world


def lidar_row(title, text, config):
    """Time one scan of the Burger's gz lidar, and one bare mj_multiRay of the same rays."""
    from service_tutorial.sim.plugins.gz_lidar import GzLidar
    world = sensor_world('burger', text)
    scan, ray = ray_sensor_times(world.models['burger'].plugin(GzLidar), world,
                                 config.scan_repeats)
    return [title, scan, ray, scan / ray, SENSOR_LIMIT, scan / ray <= SENSOR_LIMIT]


class BareDepthRender:
    """MuJoCo's own drawing of a model camera: one render, colour and depth read back."""

    def __init__(self, model, camera_id, width, height, near, far):
        from service_tutorial.sim.rendering import gl_context_class, prefer_headless_gl
        prefer_headless_gl()
        self._gl = gl_context_class()(1, 1)  # the world's backend; it draws offscreen
        self._gl.make_current()
        # A buffer of the image's size, the sensor's clipping distances (MuJoCo's are fractions
        # of the model's extent), and the world's drawing's shadows and multisampling, so that
        # both draw the same pixels the same way.
        render_model = copy.copy(model)
        render_model.vis.map.znear = near / model.stat.extent
        render_model.vis.map.zfar = far / model.stat.extent
        render_model.vis.global_.offwidth, render_model.vis.global_.offheight = width, height
        render_model.vis.quality.shadowsize = min(model.vis.quality.shadowsize, SHADOW_SIZE)
        if width * height > MULTISAMPLED_PIXELS:
            render_model.vis.quality.offsamples = 0
        self._context = mujoco.MjrContext(render_model, mujoco.mjtFontScale.mjFONTSCALE_150)
        self._model = render_model
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._scene = mujoco.MjvScene(model, maxgeom=2 * (model.ngeom + model.nsite) + 100)
        for flag in (mujoco.mjtRndFlag.mjRND_SKYBOX, mujoco.mjtRndFlag.mjRND_REFLECTION):
            self._scene.flags[flag] = False  # as a depth camera draws
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._camera.fixedcamid = camera_id
        self._option = mujoco.MjvOption()
        release_gl_context(self._gl)
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._pixels = np.empty((height, width, 3), dtype=np.uint8)
        self._depth = np.empty((height, width), dtype=np.float32)

    def render(self, data):
        """Update the scene, draw it, and read its colour and depth buffers."""
        self._gl.make_current()
        mujoco.mjv_updateScene(self._model, data, self._option, None, self._camera,
                               mujoco.mjtCatBit.mjCAT_ALL, self._scene)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        mujoco.mjr_render(self._rect, self._scene, self._context)
        mujoco.mjr_readPixels(self._pixels, self._depth, self._rect, self._context)
        release_gl_context(self._gl)  # as the world's Drawing leaves its context

    def close(self):
        """Free the rendering context and the GL context."""
        self._gl.make_current()
        self._context.free()
        self._gl.free()


def depth_camera_row(config):
    """Time one frame of surveyor's gz depth camera, and one bare render of colour and depth."""
    from service_tutorial.sim.plugins.gz_camera import GzCamera
    width, height = DEPTH_SIZE
    text = sdf_text(SURVEYOR).replace('<width>64</width><height>48</height>',
                                      f'<width>{width}</width><height>{height}</height>')
    world = sensor_world('surveyor', text)
    robot = world.models['surveyor']
    camera = robot.plugin(GzCamera)
    camera.set_active(True)
    world.step(1)  # the first frame makes the renderer and its GL context
    camera_id = robot.element_id(world.model, mujoco.mjtObj.mjOBJ_CAMERA,
                                 camera.config.site_name(camera.kind))
    bare = BareDepthRender(world.model, camera_id, width, height, camera.config.near,
                           camera.config.far)
    frames, bare_frames = [], []
    try:
        bare.render(world.data)
        for _ in range(config.camera_frames):
            start = time.perf_counter()
            camera.read()
            frames.append(time.perf_counter() - start)
            start = time.perf_counter()
            bare.render(world.data)
            bare_frames.append(time.perf_counter() - start)
    finally:
        bare.close()
        camera.close()
    if camera.depth is None or camera.depth.shape != (height, width):
        raise BenchmarkError('the gz depth camera gave no depth image of its size')
    frame, bare_frame = median_ms(frames), median_ms(bare_frames)
    return [f'{width}x{height} gz depth camera frame, surveyor (ms)', frame, bare_frame,
            frame / bare_frame, SENSOR_LIMIT, frame / bare_frame <= SENSOR_LIMIT]


def gz_sensor_table(config):
    """Measure the gz lidar and depth camera against their raw MuJoCo cost."""
    table = Table('gz_sensors', "gz-sim's sensors against bare MuJoCo", [
        ('figure', ''), ('sensor', '.3f'), ('bare', '.3f'), ('ratio', '.3f'),
        ('limit', '.2f'), ('within', '')])
    burger = sdf_text(BURGER)
    rows = burger.replace('</horizontal>', '</horizontal>' + VERTICAL_ROWS)
    table.rows = [lidar_row('360-beam gpu_lidar scan, Burger in the yard (us)', burger, config),
                  lidar_row('360 x 16-row gpu_lidar scan (us)', rows, config),
                  depth_camera_row(config)]
    table.note = ('lidars: CPU time of GzLidar.read() (the Classic RaySensor cast, REP 117 '
                  'and gz readings, noise) against mj_multiRay of the same rays on the same '
                  f'model, the medians of {config.scan_repeats} of each taken in turns. Depth '
                  f'camera: median wall time of {config.camera_frames} frames of '
                  'GzCamera.read() (snapshot, draw, depth buffer made distances along the '
                  'axis, noise) against mjv_updateScene, mjr_render and one mjr_readPixels of '
                  'colour and depth on a GL context of its own, at the same camera, clipping '
                  'distances, buffer size, shadows and multisampling. Ratio at most the limit, '
                  'as for the Classic sensors.')
    return table


def burger_sdf(name):
    """Return the Burger's SDF named name, with its topics below that name (tb3_0/scan)."""
    text = sdf_text(BURGER).replace('<model name="burger">', f'<model name="{name}">')
    for topic in BURGER_TOPICS:
        text = text.replace(f'<topic>{topic}</topic>', f'<topic>{name}/{topic}</topic>')
    return text.replace('<odom_topic>odom</odom_topic>', f'<odom_topic>{name}/odom</odom_topic>')


def create_command(name, position):
    """Return create's command line for one Burger, its SDF given with -string."""
    from ament_index_python.packages import get_package_prefix
    x, y = position
    return [os.path.join(get_package_prefix(PACKAGE), 'lib', PACKAGE, 'create'),
            '-name', name, '-string', burger_sdf(name), '-x', str(x), '-y', str(y),
            '-z', '0.01']


def resident_memory(pid):
    """Return a process's resident set size (VmRSS of /proc/<pid>/status), in bytes."""
    with open(f'/proc/{pid}/status') as status:
        for line in status:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) * 1024
    raise BenchmarkError(f'no VmRSS for process {pid}')


class BurgerWorld(ClosedOnExit):
    """mujoco_world started with the arena by world:=, three Burgers spawned by create."""

    def __init__(self, observer):
        from srv_interfaces.srv import GetModelList
        self._observer = observer
        self.start = time.monotonic()
        self.process = NodeProcess('mujoco_world', ros_args=[
            '-p', f'world:={ARENA}', '-p', 'real_time_factor:=0.0'])
        self.creates = []
        self.ready_time = self.spawned_time = self.ready_cpu_time = None
        try:
            for name, position in BURGERS.items():
                self.creates.append(subprocess.Popen(
                    create_command(name, position), stdout=subprocess.DEVNULL,
                    stderr=subprocess.PIPE, text=True))
            for srv_type, name in world_services():
                observer.wait_for_service(srv_type, name, process=self.process)
            observer.call(GetModelList, '/mujoco/get_model_list', GetModelList.Request())
            self.ready_time = time.monotonic() - self.start
            self.ready_cpu_time = self.process.cpu_time()
            for create in self.creates:
                wait_until(lambda: create.poll() is not None, 'create did not end within 60 s',
                           timeout=60.0, process=self.process)
                if create.returncode != 0:
                    raise BenchmarkError(f'create exited {create.returncode}: '
                                         f'{create.stderr.read().strip()}')
            self.spawned_time = time.monotonic() - self.start
        except BaseException:
            self.close()
            raise

    def close(self):
        """Stop every process and wait until the world's services have left the graph."""
        for create in self.creates:
            if create.poll() is None:
                create.kill()
            create.wait()
            create.stderr.close()
        self.process.stop()
        wait_until_world_gone(self._observer)


def driving_window(observer, world, seconds):
    """Drive the three, scans subscribed; return sim s per wall s and per CPU s, and scans/s."""
    from geometry_msgs.msg import Twist
    from sensor_msgs.msg import LaserScan
    node = observer.node
    command = Twist()
    command.linear.x, command.angular.z = DRIVE
    publishers = [node.create_publisher(Twist, f'/{name}/cmd_vel', 10) for name in BURGERS]
    counters = [observer.counter(LaserScan, f'/{name}/scan') for name in BURGERS]
    try:
        wait_until(lambda: all(p.get_subscription_count() > 0 for p in publishers),
                   "the world did not subscribe to every Burger's cmd_vel",
                   process=world.process)
        wait_until(lambda: all(count[0] > 0 for count, _ in counters),
                   "not every Burger's scan arrived within 30 s", process=world.process)
        for publisher in publishers:
            publisher.publish(command)
        time.sleep(0.2)
        scans = sum(count[0] for count, _ in counters)
        sim_start, wall_start, _ = sim_time_sample(observer, 'tb3_0')
        cpu_start = world.process.cpu_time()
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            for publisher in publishers:
                publisher.publish(command)
            time.sleep(min(0.5, max(0.0, end - time.monotonic())))
        sim_end, wall_end, state = sim_time_sample(observer, 'tb3_0')
        cpu = world.process.cpu_time() - cpu_start
        scans = sum(count[0] for count, _ in counters) - scans
    finally:
        for publisher in publishers:
            node.destroy_publisher(publisher)
        for _, subscription in counters:
            node.destroy_subscription(subscription)
    world.process.check()
    if abs(state.twist.angular.z) < 0.5 * DRIVE[1]:
        raise BenchmarkError('tb3_0 was not turning on cmd_vel during the measurement')
    wall, simulated = wall_end - wall_start, sim_end - sim_start
    return simulated / wall, simulated / max(cpu, 1e-9), scans / wall


def burger_world_table(observer, config):
    """Start-up, resident memory and real-time factor of three Burgers, beside Gazebo's."""
    from srv_interfaces.srv import GetModelList
    for srv_type, name in world_services():
        observer.client(srv_type, name)  # discovery starts before the process does
    ready, ready_cpu, spawned, memory, factors, per_cpu, scan_rates = ([] for _ in range(7))
    for _ in range(max(1, min(3, config.startup_runs))):
        wait_until_gone(observer, GetModelList, '/mujoco/get_model_list')
        with BurgerWorld(observer) as world:
            ready.append(world.ready_time)
            ready_cpu.append(world.ready_cpu_time)
            spawned.append(world.spawned_time)
            names = observer.call(GetModelList, '/mujoco/get_model_list',
                                  GetModelList.Request()).model_names
            if sorted(BURGERS) != sorted(set(names) & set(BURGERS)):
                raise BenchmarkError(f'the world holds {list(names)}, not the three Burgers')
            factor, factor_per_cpu, scan_rate = driving_window(observer, world,
                                                               config.real_time_window)
            factors.append(factor)
            per_cpu.append(factor_per_cpu)
            scan_rates.append(scan_rate)
            memory.append(resident_memory(world.process.process.pid) / 1e9)
    runs = len(ready)
    table = Table('gz_burgers', 'Three Burgers (lidar, IMU, DiffDrive) in an SDF arena, '
                  "beside Gazebo Harmonic headless (Robotnik's benchmark, 2025)", [
                      ('figure', ''), ('runs', 'd'), ('measured', '.3f'),
                      ('Gazebo (elsewhere)', '.2f'), ('limit', '.2f'), ('within', '')])
    ready_p50, spawned_p50 = statistics.median(ready), statistics.median(spawned)
    memory_max, factor_p50 = max(memory), statistics.median(factors)
    table.rows = [
        ['start-up: world:= to every /mujoco/ service answering, p50 (s)', runs, ready_p50,
         GAZEBO_STARTUP, GAZEBO_STARTUP, ready_p50 < GAZEBO_STARTUP],
        ['start-up: CPU time the world process had used when ready, p50 (s)', runs,
         statistics.median(ready_cpu), None, None, None],
        ['start-up: to three Burgers spawned, create exited 0, p50 (s)', runs, spawned_p50,
         GAZEBO_STARTUP, None, None],
        ['resident memory of the world process, three driving, max (GB)', runs, memory_max,
         GAZEBO_MEMORY, GAZEBO_MEMORY, memory_max < GAZEBO_MEMORY],
        ['real-time factor, three driving, scans subscribed, free-running, p50', runs,
         factor_p50, GAZEBO_REAL_TIME, GAZEBO_REAL_TIME, factor_p50 > GAZEBO_REAL_TIME],
        ['the same per CPU second of the world process (sim s per CPU s), p50', runs,
         statistics.median(per_cpu), None, None, None],
        ['scans received per wall s, three Burgers at 5 Hz, p50', runs,
         statistics.median(scan_rates), None, None, None],
    ]
    table.note = ('mujoco_world started as a user starts it (-p world:=<the arena SDF>, '
                  'real_time_factor 0) with three create processes started at the same time, '
                  'as a TurtleBot3 launch starts them; each Burger has its topics below its '
                  'name. CPU time: all threads of the world process, the steadier figure on a '
                  'shared machine, where three create processes start on the same cores. '
                  'Memory: VmRSS from /proc after the driving window. Real-time factor: '
                  'simulated s per wall s over '
                  f'{config.real_time_window} s of driving circles, from get_model_state '
                  "stamps, with a subscriber to each Burger's scan here. The Gazebo column is "
                  "Robotnik's public simulator benchmark (2025) of Gazebo Harmonic headless, "
                  'measured on another machine (start-up and memory with one robot, real-time '
                  'factor with three at its real-time target): a reference, not a measurement '
                  "of this run. Limits: start-up and memory below Gazebo's, real-time factor "
                  'above.')
    return table
