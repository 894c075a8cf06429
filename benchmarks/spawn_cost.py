"""
The cost of spawning and deleting on a ROS-free World against MuJoCo's own way of doing it.

MuJoCo's own way for a URDF file: MjSpec.from_string of its text, attach_body into a world
spec through a frame, recompile; a delete is spec.delete of the body, its frame and the
default class the attach brought, then recompile. That world spec is bare: a ground plane and
the world's physics options, with the same number of tinybots (each from_string as well)
present. The spawn_cost section of world_benchmark.py.
"""

import os
import time

from fleet import core_fleet, fleet_position, model_path, read_model
import mujoco
import numpy as np
from report import Table
from sdf_twins import sdf_twin
from service_tutorial.testing.spawns import spawn_robot

SPAWN_POSITION = (-2.0, 1.0, 1.0)
# A description the world has not seen: the same robot, its text made new by a comment.
COLD, WARM = 'cold', 'warm'
SPAWN_LIMITS = {COLD: 5.0, WARM: 1.5}
DELETE_LIMIT = 1.5
BOX_LIMIT = 2.0
# A cold spawn of a robot from SDF: at most this many times the same robot's from URDF.
SDF_LIMIT = 1.2
BOX_URDF = """<?xml version="1.0"?>
<robot name="box">
  <link name="box_link">
    <inertial><mass value="0.1"/><inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0"
      iyz="0"/></inertial>
    <collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision>
  </link>
</robot>
"""


def new_text(urdf, index):
    """Return the URDF with a comment that makes its text one the world has not seen."""
    return urdf.replace('</robot>', f'<!-- spawn {index} --></robot>')


def box_position(index):
    """Return where the index-th box of the box sequence goes: a grid, clear of the fleet."""
    return (-3.0 - 0.5 * (index % 20), 0.5 * (index // 20), 0.1)


class BareWorld:
    """A bare MjSpec world: ground, the World's physics options, robots attached by MuJoCo."""

    def __init__(self, fleet_urdf, fleet_positions, timestep=0.002):
        """Compile a world with a tinybot (from MuJoCo's own URDF import) at each position."""
        spec = mujoco.MjSpec()
        spec.copy_during_attach = True
        spec.option.timestep = timestep
        spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
        spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_PLANE, size=[25.0, 25.0, 0.05])
        self.spec = spec
        for index, position in enumerate(fleet_positions):
            self.attach(fleet_urdf, f'bot{index}', position)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)

    def attach(self, urdf, name, position):
        """Attach a robot from URDF text under the prefix '<name>::'; return body, frame."""
        child = mujoco.MjSpec.from_string(urdf)
        # MuJoCo's URDF import fixes the root to the world; the World's robots move freely.
        root = child.worldbody.first_body()
        root.add_freejoint()
        frame = self.spec.worldbody.add_frame(pos=position)
        return frame.attach_body(root, name + '::', ''), frame

    def spawn(self, urdf, name, position):
        """Attach a robot and recompile; return what delete() needs."""
        attached = self.attach(urdf, name, position)
        self.model, self.data = self.spec.recompile(self.model, self.data)
        return name, attached

    def delete(self, spawned):
        """Delete what spawn() attached, and recompile."""
        name, (body, frame) = spawned
        self.spec.delete(body)
        self.spec.delete(frame)
        default = self.spec.find_default(name + '::main')
        if default is not None:
            self.spec.delete(default)
        self.model, self.data = self.spec.recompile(self.model, self.data)


def _timed(function, *args, **kwargs):
    start = time.perf_counter()
    result = function(*args, **kwargs)
    return time.perf_counter() - start, result


def _cycles(world, bare, urdf, base_dir, calls, kind):
    """
    Spawn and delete on the World and on the bare spec in turns; return the four timings.

    Taking turns, both see the same load from anything else running on the machine.
    """
    timings = {'world spawn': [], 'world delete': [], 'bare spawn': [], 'bare delete': []}
    for index in range(calls):
        text = new_text(urdf, index) if kind == COLD else urdf
        spawn, _ = _timed(spawn_robot, world, 'spawned', text, position=SPAWN_POSITION,
                          base_dir=base_dir)
        delete, _ = _timed(world.delete_model, 'spawned')
        timings['world spawn'].append(spawn)
        timings['world delete'].append(delete)
        spawn, spawned = _timed(bare.spawn, text, 'spawned', SPAWN_POSITION)
        delete, _ = _timed(bare.delete, spawned)
        timings['bare spawn'].append(spawn)
        timings['bare delete'].append(delete)
    return timings


def spawn_rows(present, calls):
    """Return the cold spawn, warm spawn and delete rows of R2-D2 and tinybot beside present."""
    fleet_urdf = read_model('tinybot')
    positions = [fleet_position(index) for index in range(present)]
    model_dir = os.path.dirname(model_path('r2d2'))
    rows = []
    for robot in ('r2d2', 'tinybot'):
        urdf = read_model(robot)
        world = core_fleet(present, driving=False)
        bare = BareWorld(fleet_urdf, positions)
        # One cycle first: the first spawn of a process pays for imports and caches.
        _cycles(world, bare, urdf, model_dir, 1, COLD)
        for kind in (COLD, WARM):
            timings = _cycles(world, bare, urdf, model_dir, calls, kind)
            rows.append(_row(f'{kind} spawn {robot}', present, calls, timings['world spawn'],
                             timings['bare spawn'], SPAWN_LIMITS[kind]))
            if kind == WARM:
                rows.append(_row(f'delete {robot}', present, calls, timings['world delete'],
                                 timings['bare delete'], DELETE_LIMIT))
    return rows


def _row(figure, present, calls, world_samples, bare_samples, limit):
    world_p50 = float(np.median(world_samples)) * 1e3
    bare_p50 = float(np.median(bare_samples)) * 1e3
    ratio = world_p50 / bare_p50
    return [figure, present, calls, world_p50, bare_p50, ratio, limit, ratio <= limit]


def box_row(count):
    """Return the row of count box spawns then count deletes, against the same on MjSpec."""
    world = core_fleet(0, driving=False)
    start = time.perf_counter()
    for index in range(count):
        spawn_robot(world, f'box{index}', BOX_URDF, position=box_position(index))
    for index in range(count):
        world.delete_model(f'box{index}')
    world_total = time.perf_counter() - start

    bare = BareWorld('', [])
    start = time.perf_counter()
    spawned = [bare.spawn(BOX_URDF, f'box{index}', box_position(index))
               for index in range(count)]
    for one in spawned:
        bare.delete(one)
    bare_total = time.perf_counter() - start
    ratio = world_total / bare_total
    return [f'{count} box spawns then {count} deletes, total', 0, count, world_total * 1e3,
            bare_total * 1e3, ratio, BOX_LIMIT, ratio <= BOX_LIMIT]


COLUMNS = [('figure', ''), ('models present', 'd'), ('calls', 'd'), ('World p50 ms', '.3f'),
           ('MuJoCo p50 ms', '.3f'), ('ratio', '.2f'), ('limit', '.1f'), ('within', '')]
NOTE = ('World: spawn_urdf / delete_model on a ROS-free World holding that many tinybots. '
        "MuJoCo: MuJoCo's own path on a bare MjSpec (ground plane, no sky or textures) holding "
        'as many tinybots from MjSpec.from_string: from_string + a free joint on the root (as '
        'the World gives it) + attach_body + recompile; spec.delete + recompile. The two take '
        'turns. cold: every spawn a URDF text not seen before; warm: the same text again. The '
        'box row gives totals in ms, not p50s.')


def sdf_spawn_row(present, calls):
    """
    Return the row of cold spawns of R2-D2 from its SDF twin against the same from its URDF.

    Each spawn is of a text the world has not seen; SDF and URDF take turns, then the robot
    is deleted again.
    """
    urdf = read_model('r2d2')
    sdf = sdf_twin(urdf)
    model_dir = os.path.dirname(model_path('r2d2'))
    world = core_fleet(present, driving=False)
    timings = {'sdf': [], 'urdf': []}
    for index in range(calls + 1):  # the first of each warms up
        for model_format, text in (('sdf', sdf.replace('</sdf>', f'<!-- {index} --></sdf>')),
                                   ('urdf', new_text(urdf, index))):
            taken, _ = _timed(spawn_robot, world, 'spawned', text, position=SPAWN_POSITION,
                              base_dir=model_dir, model_format=model_format)
            world.delete_model('spawned')
            if index > 0:
                timings[model_format].append(taken)
    sdf_p50, urdf_p50 = (float(np.median(timings[key])) * 1e3 for key in ('sdf', 'urdf'))
    ratio = sdf_p50 / urdf_p50
    return ['cold spawn r2d2, SDF / URDF', present, calls, sdf_p50, urdf_p50, ratio, SDF_LIMIT,
            ratio <= SDF_LIMIT]


def sdf_spawn_table(config):
    """Spawn a robot from SDF on a World in this process against the same from URDF."""
    table = Table('sdf_spawn', 'Spawn from SDF on World, no ROS, against the same robot from '
                  'URDF', [('figure', ''), ('models present', 'd'), ('calls', 'd'),
                           ('SDF p50 ms', '.3f'), ('URDF p50 ms', '.3f'), ('ratio', '.2f'),
                           ('limit', '.1f'), ('within', '')])
    table.rows = [sdf_spawn_row(present, config.cost_calls) for present in config.cost_counts]
    table.note = ('R2-D2 from models/r2d2.urdf, and from its SDF twin (sdf_twins.py: the same '
                  "links, joints, inertials and shapes as sdformat's URDF import writes them), "
                  'spawned with spawn_robot on a ROS-free World holding that many tinybots '
                  'and deleted again, in turns; every text one the world has not seen (cold): '
                  'the reading, the frames and the build of the spec count, and the attach.')
    return table


def spawn_cost_table(config):
    """Spawn and delete on a World in this process against MuJoCo's own path, no ROS."""
    table = Table('spawn_cost', "Spawn and delete on World, no ROS, against MuJoCo's own path",
                  list(COLUMNS))
    for present in config.cost_counts:
        table.rows += spawn_rows(present, config.cost_calls)
    table.rows.append(box_row(config.box_count))
    table.note = NOTE
    return table
