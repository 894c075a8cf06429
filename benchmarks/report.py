"""The report: tables as text and JSON, their statistics, the targets, the machine."""

from dataclasses import dataclass, field
import datetime
import json
import os
import platform
import statistics

from harness import BenchmarkError
import mujoco
import numpy as np

# The fleet the real-time CPU target is set for. Smaller fleets print the same comparison, but
# there the world's fixed costs (/clock at 250 Hz, a tick every 20 ms) outweigh the physics.
CPU_TARGET_ROBOTS = 50
TURNING_TARGET_PERCENT = 2.0


@dataclass
class Table:
    """One section of the report: named columns, rows of values, and what they mean."""

    key: str
    title: str
    columns: list            # (heading, format) pairs; format '' leaves the value as text
    rows: list = field(default_factory=list)
    note: str = ''

    def as_dict(self):
        """Return the table as plain data for JSON."""
        return {'title': self.title, 'columns': [heading for heading, _ in self.columns],
                'rows': self.rows, 'note': self.note}

    def render(self):
        """Return the table as aligned text."""
        headings = [heading for heading, _ in self.columns]
        cells = [[_format(value, fmt) for value, (_, fmt) in zip(row, self.columns)]
                 for row in self.rows]
        widths = [max([len(h)] + [len(row[i]) for row in cells]) for i, h in enumerate(headings)]
        lines = [self.title, '  '.join(h.rjust(w) for h, w in zip(headings, widths)),
                 '  '.join('-' * w for w in widths)]
        lines += ['  '.join(c.rjust(w) for c, w in zip(row, widths)) for row in cells]
        if self.note:
            lines.append(self.note)
        return '\n'.join(lines)


def _format(value, fmt):
    if value is None:  # no limit: the row only informs
        return '-'
    if isinstance(value, bool):
        return 'yes' if value else 'NO'
    if fmt and isinstance(value, (int, float)):
        return format(value, fmt)
    return str(value)


def percentiles(samples):
    """Return p50, p95 and p99 of samples in seconds, in milliseconds."""
    if not samples:
        raise BenchmarkError('no samples to take percentiles of')
    return [float(v) * 1e3 for v in np.percentile(samples, [50, 95, 99])]


def median_ms(samples):
    """Return the median of samples in seconds, in milliseconds."""
    return float(statistics.median(samples)) * 1e3


def machine():
    """Describe the machine and software the figures come from."""
    cpu = 'unknown'
    try:
        with open('/proc/cpuinfo') as cpuinfo:
            for line in cpuinfo:
                if line.startswith('model name'):
                    cpu = line.split(':', 1)[1].strip()
                    break
    except OSError:
        pass
    import rclpy.utilities
    return {
        'nproc': os.cpu_count(),
        'cpu': cpu,
        'python': platform.python_version(),
        'mujoco': mujoco.__version__,
        'rmw': rclpy.utilities.get_rmw_implementation_identifier(),
        'load_average_at_start': [round(v, 2) for v in os.getloadavg()],
        'date': datetime.datetime.now().isoformat(timespec='seconds'),
    }


def targets(tables):
    """Return the targets of issues 5, 15, 23 and 24, their measured values, whether they hold."""
    rows = []
    by_key = {table.key: table for table in tables}
    if 'round_trips' in by_key:
        spawn = by_key['round_trips'].rows[0]
        rows.append(['spawn p50 <= Trigger p50 + 2 x core spawn p50 (ms)', spawn[2], spawn[8],
                     spawn[9]])
    if 'lesson_services' in by_key:
        for row in by_key['lesson_services'].rows:
            rows.append([f'lesson service, {row[0]} <= {row[5]:g} x MuJoCo + 2 x Trigger (ms)',
                         row[2], row[6], row[7]])
    if 'spawn_growth' in by_key:
        for row in by_key['spawn_growth'].rows:
            rows.append([f'service spawn p50 <= core + 2 x Trigger, {row[0]} present (ms)',
                         row[2], row[7], row[8]])
            rows.append([f'service delete p50 <= core + 2 x Trigger, {row[0]} present (ms)',
                         row[4], row[9], row[10]])
    if 'spawn_cost' in by_key:
        for row in by_key['spawn_cost'].rows:
            rows.append([f'World / MuJoCo, {row[0]}, {row[1]} present', row[5], row[6],
                         row[7]])
    if 'sdf_spawn' in by_key:
        for row in by_key['sdf_spawn'].rows:
            rows.append([f'{row[0]}, {row[1]} present', row[5], row[6], row[7]])
    if 'free_running' in by_key:
        for row in by_key['free_running'].rows:
            rows.append([f'free-running ratio to raw mj_step, {row[0]} robot(s)', row[3],
                         row[4], row[5]])
    if 'real_time' in by_key:
        for row in by_key['real_time'].rows:
            rows.append([f'real-time factor error %, {row[0]} robot(s)', abs(row[2]), row[3],
                         row[4]])
            if row[0] == CPU_TARGET_ROBOTS:
                rows.append([f'real-time world CPU / raw mj_step CPU, {row[0]} robot(s)',
                             row[8], row[9], row[10]])
    if 'startup' in by_key:
        row = by_key['startup'].rows[0]
        rows.append(['start-up to services ready p50 (s)', row[1], row[-2], row[-1]])
    if 'turning' in by_key:
        worst = max(abs(row[5]) for row in by_key['turning'].rows)
        rows.append(['worst turning error % on the grid', worst, TURNING_TARGET_PERCENT,
                     worst < TURNING_TARGET_PERCENT])
    if 'standard_interfaces' in by_key:
        for row in by_key['standard_interfaces'].rows:
            if row[5] is not None:
                rows.append([f'{row[0]} (ms)', row[2], row[5], row[6]])
    if 'world_loading' in by_key:
        for row in by_key['world_loading'].rows:
            rows.append([f'{row[0]} (ms)', row[2], row[6], row[7]])
    if 'web' in by_key:
        for row in by_key['web'].rows:
            rows.append([f'{row[0]} ratio, {row[1]} robot(s)', row[4], row[5], row[6]])
    if 'gz_sensors' in by_key:
        for row in by_key['gz_sensors'].rows:
            rows.append([f'{row[0]}, ratio to bare MuJoCo', row[3], row[4], row[5]])
    if 'gz_burgers' in by_key:
        for row in by_key['gz_burgers'].rows:
            if row[4] is not None:
                rows.append([f'{row[0]}, against Gazebo measured elsewhere', row[2], row[4],
                             row[5]])
    return Table('targets', 'Targets', [('target', ''), ('measured', '.3f'), ('limit', '.3f'),
                                        ('holds', '')], rows)


def write_json(path, tables, config, info):
    """Write the report as JSON, with the machine and the run's configuration."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    document = {'machine': info, 'config': config.__dict__,
                'tables': {table.key: table.as_dict() for table in tables}}
    with open(path, 'w') as json_file:
        json.dump(document, json_file, indent=2)
        json_file.write('\n')
