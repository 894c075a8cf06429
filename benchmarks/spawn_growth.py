"""The cost of a spawn and a delete through the world node as the world grows."""

from fleet import core_fleet
from harness import quiet_console
from report import median_ms, Table
from round_trips import node_round_trips


def growth_table(observer, config):
    """Measure the cost of one spawn as the world fills up with tinybots."""
    table = Table('spawn_growth', 'Spawn R2-D2 as the world grows (ms)', [
        ('models present', 'd'), ('calls', 'd'), ('spawn p50', '.2f'), ('core spawn p50', '.2f'),
        ('delete p50', '.2f'), ('core delete p50', '.2f'), ('Trigger p50', '.2f'),
        ('spawn limit', '.2f'), ('within', ''), ('delete limit', '.2f'), ('delete within', '')])
    for count in config.growth_counts:
        with quiet_console(config.log_path):
            node = node_round_trips(observer, count, config.growth_calls, with_reset=False,
                                    core=core_fleet(count, driving=False))
        spawn_p50, core_spawn_p50 = median_ms(node['spawn']), median_ms(node['core spawn'])
        delete_p50, core_delete_p50 = median_ms(node['delete']), median_ms(node['core delete'])
        trivial_p50 = median_ms(node['trigger'])
        spawn_limit = core_spawn_p50 + 2.0 * trivial_p50
        delete_limit = core_delete_p50 + 2.0 * trivial_p50
        table.rows.append([count, len(node['spawn']), spawn_p50, core_spawn_p50, delete_p50,
                           core_delete_p50, trivial_p50, spawn_limit, spawn_p50 <= spawn_limit,
                           delete_limit, delete_p50 <= delete_limit])
    table.note = ('every spawn recompiles the whole model, so its cost grows with the world; '
                  'limit = core p50 + 2 x Trigger p50 (the service may cost two trivial round '
                  'trips more than the same operation on World). Each round times the core '
                  'spawn and delete (a ROS-free World with the same models, the world of the '
                  'node paused meanwhile), then the service spawn and delete, then one Trigger')
    return table
