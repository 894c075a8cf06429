"""Free-running speed and real time: mujoco_world against bare mj_step of its fleet."""

import statistics

from fleet import FleetWorld, RawFleet
from report import CPU_TARGET_ROBOTS, Table

CPU_LIMIT_RATIO = 2.0


def alternating_windows(observer, count, real_time_factor, window, config):
    """
    Alternate windows of bare mj_step (world paused) and of the world node, round by round.

    Adjacent windows see the same load on a shared machine. Yield bare mj_step's RawFleet.window
    figures and the world's FleetWorld.window figures of each round.
    """
    raw = RawFleet(count)
    with FleetWorld(observer, count, real_time_factor) as world:
        world.fleet.drive_for(config.warm_up)
        for _ in range(config.speed_rounds):
            world.physics('pause_physics')
            raw_figures = raw.window(config.speed_window)
            world.physics('unpause_physics')
            world.fleet.drive_for(config.speed_settle)
            yield raw_figures, world.window(window)


def free_running_rounds(observer, count, config):
    """Return the free-running world node's figures against bare mj_step, medians of rounds."""
    rounds = []
    for (raw_speed, raw_cpu), (node_speed, node_cpu, clock_rate, odom_rate) in \
            alternating_windows(observer, count, 0.0, config.speed_window, config):
        rounds.append((node_speed, raw_speed, node_speed / raw_speed, node_cpu / raw_cpu,
                       clock_rate, odom_rate))
    return [statistics.median(column) for column in zip(*rounds)]


def real_time_rounds(observer, count, config):
    """
    Return the world node's figures in real time against bare mj_step, medians of rounds.

    They are the achieved factor, the world's CPU share (%), the CPU share bare mj_step of the
    same fleet needs for real time (%), the ratio of the two in each round, and the /clock and
    odom rates.
    """
    rounds = []
    for (_, raw_per_cpu_second), (factor, per_cpu_second, clock_rate, odom_rate) in \
            alternating_windows(observer, count, 1.0, config.real_time_window, config):
        world_cpu, raw_cpu = 100.0 * factor / per_cpu_second, 100.0 / raw_per_cpu_second
        rounds.append((factor, world_cpu, raw_cpu, world_cpu / raw_cpu, clock_rate, odom_rate))
    return [statistics.median(column) for column in zip(*rounds)]


def speed_tables(observer, config):
    """Free-running speed against raw mj_step, and the real-time factor achieved."""
    speed = Table('free_running', 'Free-running speed, real_time_factor 0 (simulated s per '
                  'wall s)', [
                      ('robots', 'd'), ('world node', '.1f'), ('raw mj_step', '.1f'),
                      ('ratio', '.3f'), ('target ratio', '.1f'), ('within', ''),
                      ('CPU-time ratio', '.3f'), ('/clock msgs/s', '.0f'),
                      ('bot0 odom msgs/s', '.0f')])
    real_time = Table('real_time', 'Real time, real_time_factor 1', [
        ('robots', 'd'), ('achieved factor', '.4f'), ('error %', '.2f'), ('limit %', '.1f'),
        ('within', ''), ('raw mj_step x real time', '.1f'), ('world CPU %', '.0f'),
        ('raw mj_step CPU %', '.1f'), ('CPU ratio', '.2f'), ('CPU limit ratio', '.1f'),
        ('CPU within', ''),
        ('/clock msgs/s', '.0f'), ('bot0 odom msgs/s', '.0f')])
    for count in config.robot_counts:
        node, raw, ratio, cpu_ratio, clock_rate, odom_rate = free_running_rounds(
            observer, count, config)
        target = 0.7 if count == 1 else 0.8
        speed.rows.append([count, node, raw, ratio, target, ratio >= target, cpu_ratio,
                           clock_rate, odom_rate])
        factor, world_cpu, raw_cpu_percent, cpu_ratio, clock_rate, odom_rate = \
            real_time_rounds(observer, count, config)
        error = 100.0 * (factor - 1.0)
        real_time.rows.append([count, factor, error, 1.0, abs(error) <= 1.0, raw, world_cpu,
                               raw_cpu_percent, cpu_ratio, CPU_LIMIT_RATIO,
                               cpu_ratio <= CPU_LIMIT_RATIO, clock_rate, odom_rate])
    speed.note = ('world node: the mujoco_world executable in its own process, every robot '
                  'driving on /cmd_vel, /clock and bot0/odom subscribed to here (msgs/s: what '
                  'arrived per wall s). raw mj_step: the same fleet compiled in this process, '
                  'no ROS, stepped while the world node is paused. Medians of '
                  f'{config.speed_rounds} alternating rounds of {config.speed_window} s. '
                  'CPU-time ratio: the same per CPU second used (every thread of the world '
                  'process), which other load on a shared machine skews less. Target ratio '
                  '0.7 with 1 robot, 0.8 with more.')
    real_time.note = ('achieved factor over each window from get_model_state stamps; raw '
                      'mj_step x real time is how much faster than real time the physics '
                      'alone could run (from the free-running rows); world CPU %: CPU time '
                      'of the world process per wall second; raw mj_step CPU %: the CPU share '
                      'bare mj_step of the same fleet needs for real time (its simulated s per '
                      'CPU s, stepped in this process while the world node is paused); CPU '
                      'ratio: world CPU over raw mj_step CPU, the two windows of a round '
                      f'taken together; at most {CPU_LIMIT_RATIO} (the target is set for '
                      f'{CPU_TARGET_ROBOTS} robots; with fewer, /clock at 250 Hz and a tick '
                      'every 20 ms cost more than the physics). Medians of '
                      f'{config.speed_rounds} alternating rounds: {config.speed_window} s of '
                      f'bare mj_step, then {config.real_time_window} s of the world node')
    return speed, real_time
