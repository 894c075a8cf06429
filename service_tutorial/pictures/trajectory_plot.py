"""
A robot's planar trajectory as an SVG figure, drawn without a plotting library.

Left panel: the path seen from above (x to the right, y up, one metre as long on both axes),
with arrows along it that show where the robot was heading. Right panel: the heading over
time, unwrapped so that a robot turning on the spot draws a straight ramp.
"""

import math
from xml.sax.saxutils import escape

import numpy as np

FIGURE_WIDTH, FIGURE_HEIGHT = 900, 445
PANEL_TOP, PANEL_SIZE = 50, 320
PATH_LEFT, HEADING_LEFT, HEADING_WIDTH = 70, 490, 380
ARROW_COUNT = 16
MIN_PATH_SPAN = 0.4  # m: a robot turning on the spot still gets a readable fan of arrows
PATH_COLOUR, START_COLOUR, END_COLOUR = '#1f5fa8', '#2a9d3f', '#c0392b'


def nice_ticks(low, high, count=5):
    """Round tick values (1, 2 or 5 times a power of ten apart) that cover low..high."""
    span = high - low
    if span <= 0.0:
        return [low]
    raw_step = span / count
    magnitude = 10.0 ** math.floor(math.log10(raw_step))
    step = next(m * magnitude for m in (1.0, 2.0, 5.0, 10.0) if m * magnitude >= raw_step)
    first = math.ceil(low / step - 1e-9)
    last = math.floor(high / step + 1e-9)
    return [round(i * step, 10) for i in range(first, last + 1)]


def _number(value):
    """Format a tick label without trailing zeros."""
    return f'{value:.6g}'


class Panel:
    """A rectangle of the figure that maps data coordinates to SVG pixels (y up)."""

    def __init__(self, left, top, width, height, x_range, y_range):
        self.left, self.top, self.width, self.height = left, top, width, height
        self.x_range, self.y_range = x_range, y_range

    def to_pixels(self, x, y):
        """Convert data points to SVG coordinates."""
        (x0, x1), (y0, y1) = self.x_range, self.y_range
        px = self.left + (np.asarray(x, dtype=float) - x0) / (x1 - x0) * self.width
        py = self.top + self.height - (np.asarray(y, dtype=float) - y0) / (y1 - y0) * self.height
        return px, py

    def axes(self, x_label, y_label, title):
        """Draw the frame, grid, tick labels, axis labels and title of the panel."""
        parts = [f'<rect x="{self.left}" y="{self.top}" width="{self.width}" '
                 f'height="{self.height}" fill="white" stroke="#444"/>']
        for tick in nice_ticks(*self.x_range):
            px, _ = self.to_pixels(tick, self.y_range[0])
            parts.append(f'<line x1="{px:.1f}" y1="{self.top}" x2="{px:.1f}" '
                         f'y2="{self.top + self.height}" stroke="#ddd"/>')
            parts.append(f'<text x="{px:.1f}" y="{self.top + self.height + 16}" '
                         f'text-anchor="middle">{_number(tick)}</text>')
        for tick in nice_ticks(*self.y_range):
            _, py = self.to_pixels(self.x_range[0], tick)
            parts.append(f'<line x1="{self.left}" y1="{py:.1f}" x2="{self.left + self.width}" '
                         f'y2="{py:.1f}" stroke="#ddd"/>')
            parts.append(f'<text x="{self.left - 6}" y="{py + 4:.1f}" '
                         f'text-anchor="end">{_number(tick)}</text>')
        centre_x = self.left + self.width / 2
        centre_y = self.top + self.height / 2
        parts.append(f'<text x="{centre_x:.1f}" y="{self.top + self.height + 36}" '
                     f'text-anchor="middle">{escape(x_label)}</text>')
        parts.append(f'<text x="{self.left - 46}" y="{centre_y:.1f}" text-anchor="middle" '
                     f'transform="rotate(-90 {self.left - 46} {centre_y:.1f})">'
                     f'{escape(y_label)}</text>')
        parts.append(f'<text x="{centre_x:.1f}" y="{self.top - 12}" text-anchor="middle" '
                     f'font-weight="bold">{escape(title)}</text>')
        return parts


def _polyline(element_id, px, py, colour):
    points = ' '.join(f'{a:.2f},{b:.2f}' for a, b in zip(px, py))
    return (f'<polyline id="{element_id}" points="{points}" fill="none" stroke="{colour}" '
            'stroke-width="2" stroke-linejoin="round"/>')


def _padded_range(values, minimum_span, margin=0.15):
    """Find a range around values, at least minimum_span wide, with a margin each side."""
    low, high = float(np.min(values)), float(np.max(values))
    span = max(high - low, minimum_span)
    centre = (low + high) / 2
    return centre - span * (0.5 + margin), centre + span * (0.5 + margin)


def _path_panel(x, y, yaw):
    """Draw the top-down view: path, start and end, heading arrows coloured by time."""
    x_range = _padded_range(x, MIN_PATH_SPAN)
    y_range = _padded_range(y, MIN_PATH_SPAN)
    # One scale on both axes: widen the narrower range to the wider one's span.
    span = max(x_range[1] - x_range[0], y_range[1] - y_range[0])
    x_range = (sum(x_range) / 2 - span / 2, sum(x_range) / 2 + span / 2)
    y_range = (sum(y_range) / 2 - span / 2, sum(y_range) / 2 + span / 2)
    panel = Panel(PATH_LEFT, PANEL_TOP, PANEL_SIZE, PANEL_SIZE, x_range, y_range)
    parts = panel.axes('x (m)', 'y (m)', 'Path seen from above')
    px, py = panel.to_pixels(x, y)
    parts.append(_polyline('trajectory', px, py, PATH_COLOUR))
    # Arrows in pixels: long for a robot that stayed on its spot (a fan), short along a path.
    extent = max(np.ptp(x), np.ptp(y)) / span
    arrow_length = (0.3 if extent < 0.1 else 0.09) * PANEL_SIZE
    parts.append('<g id="heading-arrows" stroke-width="2">')
    samples = np.unique(np.linspace(0, len(x) - 1, min(ARROW_COUNT, len(x))).round().astype(int))
    for order, i in enumerate(samples):
        # Early arrows light, late ones dark.
        shade = 0.75 * (1.0 - order / max(1, len(samples) - 1))
        colour = '#{0:02x}{0:02x}{1:02x}'.format(int(40 + 200 * shade), int(90 + 160 * shade))
        tip_x = px[i] + arrow_length * math.cos(yaw[i])
        tip_y = py[i] - arrow_length * math.sin(yaw[i])
        head = []
        for side in (2.6, -2.6):  # the two barbs of the head, about 30 degrees off the shaft
            head.append(f'{tip_x + 8 * math.cos(yaw[i] + side):.2f},'
                        f'{tip_y - 8 * math.sin(yaw[i] + side):.2f}')
        parts.append(f'<line x1="{px[i]:.2f}" y1="{py[i]:.2f}" x2="{tip_x:.2f}" '
                     f'y2="{tip_y:.2f}" stroke="{colour}"/>')
        parts.append(f'<polyline points="{head[0]} {tip_x:.2f},{tip_y:.2f} {head[1]}" '
                     f'fill="none" stroke="{colour}"/>')
    parts.append('</g>')
    parts.append(f'<circle cx="{px[0]:.2f}" cy="{py[0]:.2f}" r="5" fill="{START_COLOUR}"/>')
    parts.append(f'<circle cx="{px[-1]:.2f}" cy="{py[-1]:.2f}" r="5" fill="{END_COLOUR}"/>')
    return parts


def _heading_panel(times, yaw):
    """Draw the heading in degrees, unwrapped, over time."""
    degrees = np.degrees(np.unwrap(yaw))
    t_range = (float(times[0]), float(times[-1]))
    if t_range[1] <= t_range[0]:
        t_range = (t_range[0] - 0.5, t_range[0] + 0.5)
    panel = Panel(HEADING_LEFT, PANEL_TOP, HEADING_WIDTH, PANEL_SIZE, t_range,
                  _padded_range(degrees, 10.0, margin=0.05))
    parts = panel.axes('time (s)', 'heading (degrees)', 'Heading over time')
    px, py = panel.to_pixels(times, degrees)
    parts.append(_polyline('heading', px, py, PATH_COLOUR))
    return parts


def write_trajectory_plot(path, times, x, y, yaw, title='tinybot'):
    """Write times (s), positions x, y (m) and headings yaw (rad) as a two-panel SVG file."""
    times, x, y, yaw = (np.asarray(values, dtype=float).reshape(-1)
                        for values in (times, x, y, yaw))
    if not len(times) == len(x) == len(y) == len(yaw) or len(times) == 0:
        raise ValueError(f'times, x, y and yaw must be equally long and not empty, got lengths '
                         f'{len(times)}, {len(x)}, {len(y)}, {len(yaw)}')
    if not np.all(np.isfinite([times, x, y, yaw])):
        raise ValueError('times, x, y and yaw must be finite numbers')
    parts = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{FIGURE_WIDTH}" '
             f'height="{FIGURE_HEIGHT}" viewBox="0 0 {FIGURE_WIDTH} {FIGURE_HEIGHT}" '
             'font-family="DejaVu Sans, Arial, sans-serif" font-size="12" fill="#222">',
             f'<title>{escape(title)}: path and heading</title>',
             f'<rect width="{FIGURE_WIDTH}" height="{FIGURE_HEIGHT}" fill="white"/>',
             f'<text x="{FIGURE_WIDTH / 2}" y="22" text-anchor="middle" font-size="15" '
             f'font-weight="bold">{escape(title)}: {times[-1] - times[0]:.2f} s, '
             f'{len(times)} odometry samples</text>']
    parts += _path_panel(x, y, yaw)
    parts += _heading_panel(times, yaw)
    legend_y = FIGURE_HEIGHT - 12
    parts += [f'<circle cx="{PATH_LEFT + 5}" cy="{legend_y - 4}" r="5" fill="{START_COLOUR}"/>',
              f'<text x="{PATH_LEFT + 14}" y="{legend_y}">start</text>',
              f'<circle cx="{PATH_LEFT + 60}" cy="{legend_y - 4}" r="5" fill="{END_COLOUR}"/>',
              f'<text x="{PATH_LEFT + 69}" y="{legend_y}">end</text>',
              f'<text x="{PATH_LEFT + 110}" y="{legend_y}">arrows: heading, light (early) '
              'to dark (late)</text>']
    parts.append('</svg>')
    with open(path, 'w') as svg_file:
        svg_file.write('\n'.join(parts) + '\n')
    return path
