"""
What the world's web page costs: nothing without a browser, at most 1.5x the CPU with one.

mujoco_world runs as a process with a driving fleet (fleet.FleetWorld), once with web:=false
and once with web:=true and no browser, for the free-running speed and the real-time CPU; then
with web:=true, 50 robots in real time, alternately with no page open and with one headless
Chromium (Debian's, through selenium) showing the page.
"""

import shutil
import socket
import statistics
import time

from fleet import FleetWorld
from harness import BenchmarkError
from report import Table

# Without a browser the page must cost nothing: within run-to-run noise of web:=false, taken
# as 10 %; with one browser the world process may use at most 1.5x the CPU.
NOISE = 0.10
BROWSER_CPU_LIMIT = 1.5
CHROMIUM_ARGUMENTS = ('--headless=new', '--enable-unsafe-swiftshader', '--use-angle=swiftshader',
                      '--no-sandbox', '--disable-dev-shm-usage', '--window-size=1280,800')


def free_port():
    """Return a TCP port on localhost that nothing listens on now."""
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        return probe.getsockname()[1]


def chromium_ready():
    """Tell whether Chromium, its driver and selenium are there for the browser row."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return False
    return bool(shutil.which('chromium') and shutil.which('chromedriver'))


def start_browser():
    """Start one headless Chromium on a blank page."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service
    options = webdriver.ChromeOptions()
    options.binary_location = shutil.which('chromium')
    for argument in CHROMIUM_ARGUMENTS:
        options.add_argument(argument)
    return webdriver.Chrome(options=options, service=Service(shutil.which('chromedriver')))


def cpu_cost(world, config):
    """Return the world process's CPU ms per simulated s over one window of driving."""
    _, per_cpu_second, _, _ = world.window(config.web_window)
    return 1e3 / per_cpu_second


def world_window(observer, count, real_time_factor, web, config):
    """Return the CPU ms per simulated s of one window of a new world."""
    parameters = {'web': True, 'web_port': free_port()} if web else {}
    with FleetWorld(observer, count, real_time_factor, **parameters) as world:
        world.fleet.drive_for(config.warm_up)
        return cpu_cost(world, config)


def without_and_with_web(observer, real_time_factor, config):
    """
    Return the medians of world_window() with web:=false and with web:=true (no browser).

    The two worlds take turns, round by round, so that both see the same load of a shared
    machine.
    """
    rounds = {False: [], True: []}
    for _ in range(config.web_rounds):
        for web in rounds:
            rounds[web].append(world_window(observer, 1, real_time_factor, web, config))
    return [statistics.median(rounds[web]) for web in rounds]


def show_page(browser, address, *, timeout=60.0):
    """Load the page and wait until its panel is there (its websocket is connected)."""
    browser.get(address)
    deadline = time.monotonic() + timeout
    while not browser.find_elements('xpath', "//button[normalize-space()='Spawn R2-D2']"):
        if time.monotonic() > deadline:
            raise BenchmarkError(f'the page at {address} showed no panel within {timeout} s')
        time.sleep(0.1)


def browser_figures(observer, config):
    """Return the world's CPU ms per simulated s with no page open and with one, medians."""
    port = free_port()
    browser = start_browser()
    rounds = []
    try:
        with FleetWorld(observer, config.web_robots, 1.0, web=True, web_port=port) as world:
            world.fleet.drive_for(config.warm_up)
            for _ in range(config.web_rounds):
                browser.get('about:blank')  # the page's connection ends
                world.fleet.drive_for(config.warm_up)
                without = cpu_cost(world, config)
                show_page(browser, f'http://127.0.0.1:{port}')
                world.fleet.drive_for(config.warm_up)
                rounds.append((without, cpu_cost(world, config)))
    finally:
        browser.quit()
    return [statistics.median(column) for column in zip(*rounds)]


def web_table(observer, config):
    """Measure the page's cost with no browser against web:=false, and with one browser."""
    table = Table('web', "The web page's cost", [
        ('case', ''), ('robots', 'd'), ('CPU ms per sim s', '.1f'), ('against', '.1f'),
        ('ratio', '.3f'), ('limit', '.2f'), ('within', '')])
    for real_time_factor, mode in ((0.0, 'free-running'), (1.0, 'real time')):
        off, on = without_and_with_web(observer, real_time_factor, config)
        table.rows.append([f'{mode}: web:=false / web:=true, no browser', 1, off, on, on / off,
                           1.0 + NOISE, on / off <= 1.0 + NOISE])
    if not chromium_ready():
        raise BenchmarkError('the browser row needs chromium, chromium-driver (apt) and '
                             'selenium (scripts/setup)')
    without, with_page = browser_figures(observer, config)
    table.rows.append(['real time: web:=true, no browser / one browser',
                       config.web_robots, without, with_page, with_page / without,
                       BROWSER_CPU_LIMIT, with_page / without <= BROWSER_CPU_LIMIT])
    table.note = ('mujoco_world as a process, every robot driving on cmd_vel (FleetWorld, as '
                  'the speed rows). CPU ms per sim s: CPU time of the world process (every '
                  'thread) per simulated second, in the first case; against: in the second; '
                  'ratio: second over first. Per simulated second, because a browser '
                  'rendering WebGL in software on the same cores slows the world down, and '
                  'CPU per wall second would then fall. The browser: Debian’s headless '
                  'chromium through selenium, its own CPU not counted; between rounds it '
                  'leaves the page (about:blank). The first two rows: a new world per window, '
                  'web:=false and web:=true taking turns. Medians of '
                  f'{config.web_rounds} windows of {config.web_window} s; noise allowance '
                  f'{NOISE:.0%}.')
    return table
