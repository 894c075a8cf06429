"""
gz-math's SpeedLimiter: how gz-sim's DiffDrive limits its speeds, free of ROS.

Each physics step DiffDrive limits its commanded linear and angular speed, each on its own, in
gz's order: the jerk (from the two speeds before), then the acceleration (from the speed
before), then the speed itself, each clamped to [min, max]; a limit not given is none. A speed
limited by acceleration alone follows a ramp at the acceleration limit until it reaches its
target, which a Ramp gives in closed form; jerk limits are applied step by step (limit()).
"""

from dataclasses import dataclass
import math

KINDS = ('velocity', 'acceleration', 'jerk')


@dataclass(frozen=True)
class SpeedLimits:
    """The limits of one speed (m/s or rad/s, and their rates): gz-math's, none by default."""

    min_velocity: float = -math.inf
    max_velocity: float = math.inf
    min_acceleration: float = -math.inf
    max_acceleration: float = math.inf
    min_jerk: float = -math.inf
    max_jerk: float = math.inf

    @property
    def jerk_limited(self):
        """Tell whether the jerk is limited, which only a step-by-step limit() follows."""
        return math.isfinite(self.min_jerk) or math.isfinite(self.max_jerk)

    def limit(self, speed, previous, before_previous, timestep):
        """Return a commanded speed limited as gz-math does, given the two limited before it."""
        acceleration_before = (previous - before_previous) / timestep
        acceleration = _clamp((speed - previous) / timestep, acceleration_before
                              + self.min_jerk * timestep,
                              acceleration_before + self.max_jerk * timestep)
        acceleration = _clamp(acceleration, self.min_acceleration, self.max_acceleration)
        return _clamp(previous + acceleration * timestep, self.min_velocity, self.max_velocity)

    def ramp(self, start, target, now, timestep):
        """Return the Ramp from speed start to a target, under the acceleration limits alone."""
        target = _clamp(target, self.min_velocity, self.max_velocity)
        change = target - start
        rate = self.max_acceleration if change > 0.0 else self.min_acceleration
        if change == 0.0 or not math.isfinite(rate):
            return Ramp(target, target, 0.0, now, now)
        # Whole steps at the limit; the step after them reaches the target exactly.
        steps = math.floor(abs(change) / (abs(rate) * timestep))
        return Ramp(start, target, rate, now, now + steps * timestep)


def _clamp(value, low, high):
    return min(max(value, low), high)


@dataclass(frozen=True)
class Ramp:
    """A speed that changes at a constant rate from start (at begin) until end, then is target."""

    start: float
    target: float
    rate: float  # per s
    begin: float  # s of simulation time
    end: float

    def speed(self, now):
        """Return the speed at simulation time now."""
        if now >= self.end:
            return self.target
        return self.start + self.rate * (now - self.begin)

    def rate_at(self, now):
        """Return how fast the speed changes at simulation time now (0 once it is reached)."""
        return self.rate if now < self.end else 0.0


def read_limits(parameters, axis):
    """
    Return the SpeedLimits of one axis ('linear' or 'angular') of a DiffDrive block.

    <min_velocity>... set both axes; <min_linear_velocity>... one, over them. Every minimum
    must be at most 0 and every maximum at least 0: gz-math clamps each step's change of
    speed to [min, max], and a robot with a positive minimum could never stop.
    """
    values = {}
    for kind in KINDS:
        for end in ('min', 'max'):
            tag = next((tag for tag in (f'{end}_{axis}_{kind}', f'{end}_{kind}')
                        if parameters.has(tag)), None)
            if tag is None:
                continue
            bound = {'maximum': 0.0} if end == 'min' else {'minimum': 0.0}
            values[f'{end}_{kind}'] = parameters.number(tag, None, **bound)
    return SpeedLimits(**values)
