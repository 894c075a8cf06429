"""The benchmark (benchmarks/world_benchmark.py) runs end to end with tiny counts."""

import json
import math
import os
import sys

from ament_flake8.main import main_with_errors
from ament_pep257.main import main as pep257_main
import pytest
from repository import ROOT

BENCHMARKS = os.path.join(ROOT, 'benchmarks')
sys.path.insert(0, BENCHMARKS)

import report  # noqa: E402, I100  (benchmarks/ is not a package)
import web_page  # noqa: E402
import world_benchmark  # noqa: E402

QUICK = world_benchmark.QUICK
# The gz section: a 360-beam and a 16-row lidar and a depth camera against bare MuJoCo; three
# Burgers' start-up (wall and CPU), time to spawned, memory, real-time factor (per wall and
# per CPU second) and scans received, three of them with a limit. The targets: the three
# sensor rows and those three.
GZ_ROWS = {'gz_sensors': 3, 'gz_burgers': 7}
GZ_TARGETS = 3 + 3
# Table key -> expected number of rows for the QUICK configuration.
EXPECTED_ROWS = {
    'round_trips': 4,
    # a warm and a cold spawn and a delete of R2-D2 through the lesson's services
    'lesson_services': 3,
    'spawn_growth': len(QUICK.growth_counts),
    'free_running': len(QUICK.robot_counts),
    'real_time': len(QUICK.robot_counts),
    'startup': 1,
    'turning': len(QUICK.durations) * len(QUICK.velocities),
    'targets': (1 + 3 + 2 * len(QUICK.growth_counts) + 6 * len(QUICK.cost_counts) + 1
                + 2 * len(QUICK.robot_counts)
                + (report.CPU_TARGET_ROBOTS in QUICK.robot_counts) + 1 + 1 + 5 + 3 + 3
                + len(QUICK.cost_counts) + GZ_TARGETS),
    # a spawn of R2-D2, World.step against mj_step, a box against the hull of many points
    'core': 3,
    # cold spawn, warm spawn and delete of two robots per world size, and the box sequence
    'spawn_cost': 6 * len(QUICK.cost_counts) + 1,
    # a cold spawn of R2-D2 from SDF against the same from URDF, per world size
    'sdf_spawn': len(QUICK.cost_counts),
    'camera': 1,
    'sensors': 5,
    'answers': 3,
    # SpawnEntities against MuJoCo's batch and against single spawns, StepSimulation, calls
    # during it, states from a C client, and (no limit) from rclpy's client
    'standard_interfaces': 6,
    # LoadWorld of the parking world, the yard and the yard in SDF, each against the core's
    # build of it
    'world_loading': 3,
    # the web page: no browser against web:=false, free-running and in real time; one browser
    'web': 3,
    **GZ_ROWS,
}


def check_cell(table, heading, fmt, value):
    """Numeric columns hold finite numbers, 'within' columns booleans, text columns text."""
    where = f'{table.key}[{heading}]'
    if value is None and heading in ('limit', 'within'):  # a row that only informs
        return
    if value is None and heading.endswith('(elsewhere)'):  # no reference for this row
        return
    if heading in ('within', 'holds') or heading.endswith(' within'):
        assert isinstance(value, bool), where
    elif fmt:
        assert isinstance(value, (int, float)) and not isinstance(value, bool), where
        assert math.isfinite(value), where
    else:
        assert isinstance(value, str) and value, where


@pytest.mark.ros
@pytest.mark.long
def test_quick_benchmark_fills_every_table(rclpy_session, tmp_path):
    config = world_benchmark.Config(**QUICK.__dict__)
    config.log_path = str(tmp_path / 'nodes.log')
    printed = []
    # Every section but gz, which the next test runs alone and checks row by row.
    expected = {key: rows for key, rows in EXPECTED_ROWS.items() if key not in GZ_ROWS}
    expected['targets'] -= GZ_TARGETS
    sections = tuple(section for section in world_benchmark.SECTIONS if section != 'gz')
    if not web_page.chromium_ready():  # scripts/test installs it as root; else left out
        sections = tuple(section for section in sections if section != 'web')
        expected['targets'] -= expected.pop('web')
    tables = world_benchmark.run(config, sections=sections, report=printed.append)

    assert {table.key: len(table.rows) for table in tables} == expected
    for table in tables:
        assert table.rows, table.key
        for row in table.rows:
            assert len(row) == len(table.columns), table.key
            for value, (heading, fmt) in zip(row, table.columns):
                check_cell(table, heading, fmt, value)
    assert len(printed) == len(tables)
    assert all(table.title in text for table, text in zip(tables, printed))

    path = tmp_path / 'benchmark.json'
    world_benchmark.write_json(str(path), tables, config, world_benchmark.machine())
    document = json.loads(path.read_text())
    assert document['machine']['nproc'] >= 1
    assert set(document['tables']) == set(expected)
    for key, table in document['tables'].items():
        assert all(len(row) == len(table['columns']) for row in table['rows']), key


@pytest.mark.ros
@pytest.mark.long
def test_the_gz_section_alone_fills_its_tables(rclpy_session, tmp_path):
    config = world_benchmark.Config(**QUICK.__dict__)
    config.log_path = str(tmp_path / 'nodes.log')
    tables = world_benchmark.run(config, sections=('gz',), report=lambda _: None)

    expected = {**GZ_ROWS, 'targets': GZ_TARGETS}
    assert {table.key: len(table.rows) for table in tables} == expected
    for table in tables:
        for row in table.rows:
            for value, (heading, fmt) in zip(row, table.columns):
                check_cell(table, heading, fmt, value)
    burgers = next(table for table in tables if table.key == 'gz_burgers')
    start_up, cpu, spawned, memory, factor, per_cpu, scans = (row[2] for row in burgers.rows)
    assert 0.0 < start_up <= spawned and cpu > 0.0 and memory > 0.0
    assert factor > 0.0 and per_cpu > 0.0 and scans > 0.0
    assert [row[3] for row in burgers.rows] == [4.3, None, 4.3, 1.45, 0.66, None, None]


def test_command_line_options():
    config, sections, path = world_benchmark.parse_args(
        ['--quick', '--robots', '1,3', '--calls', '7', '--json', 'x.json',
         '--sections', 'speed,startup,standard'])
    assert config.robot_counts == (1, 3) and config.calls == 7
    assert sections == ('speed', 'startup', 'standard') and path == 'x.json'
    full, all_sections, default_path = world_benchmark.parse_args([])
    assert full.calls >= 200 and full.robot_counts == (1, 10, 50)
    # The issue's figures for the standard interfaces' rows.
    assert (full.standard_batch, full.standard_steps, full.standard_step_robots) == \
        (50, 10_000, 10)
    assert all_sections == world_benchmark.SECTIONS
    assert default_path.endswith(os.path.join('output', 'benchmark.json'))
    with pytest.raises(SystemExit):
        world_benchmark.parse_args(['--sections', 'nonsense'])


@pytest.mark.linter
def test_benchmarks_follow_the_code_style():
    rc, errors = main_with_errors(argv=[BENCHMARKS])
    assert rc == 0, 'flake8:\n' + '\n'.join(errors)
    assert pep257_main(argv=[BENCHMARKS]) == 0
