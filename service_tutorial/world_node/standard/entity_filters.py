"""
The standard's EntityFilters, checked and applied to the world's entities.

Every filter given applies: the name pattern (a POSIX ERE, name_patterns.py), the categories
(any of them), the tags (any or all of them) and the bounds (a sphere, a box or a convex hull
that the entity's collision geometry overlaps; sim/bounds.py). A filter that cannot be applied
is refused before any entity is looked at, with a message naming the value.
"""

import math

import numpy as np
from service_tutorial.sim import bounds
from service_tutorial.sim.validation import quoted
from service_tutorial.world_node.answers import Refusal
from service_tutorial.world_node.standard.entity_messages import entity_info
from service_tutorial.world_node.standard.name_patterns import NamePattern, PatternError
from simulation_interfaces.msg import Bounds, Result, TagsFilter

# More points than a hull needs; beyond it a request is refused before any work.
MAX_HULL_POINTS = 10000
MAX_FILTER_TAGS = 1000


class EntityFilter:
    """One request's filters, checked; matches(model) applies them all."""

    def __init__(self, filters, world):
        """Check filters (an EntityFilters message), or raise a Refusal naming the value."""
        self._world = world
        self._pattern = _pattern(filters.filter)
        self._categories = {category.category for category in filters.categories}
        self._tags = tags_test(filters.tags)
        self._overlaps = _bounds_test(filters.bounds)

    def matches(self, model):
        """Return True if a model passes every filter."""
        if self._pattern is not None and not self._pattern.search(model.name):
            return False
        if self._categories or self._tags is not None:
            # Only these two read the EntityInfo, which a model without one builds anew.
            info = entity_info(model)
            if self._categories and info.category.category not in self._categories:
                return False
            if self._tags is not None and not self._tags(set(info.tags)):
                return False
        return self._overlaps is None or self._overlaps(
            bounds.collision_boxes(self._world, model))


def _pattern(text):
    if not text:
        return None
    try:
        return NamePattern(text)
    except PatternError as error:
        raise Refusal(Result.RESULT_OPERATION_FAILED, f'name filter {quoted(text)} is not a '
                      f'POSIX extended regular expression this world runs: {error}') from None


def tags_test(tags_filter):
    """Return a test of a set of tags against a TagsFilter, None for no tags; or refuse it."""
    wanted = set(tags_filter.tags)
    if len(tags_filter.tags) > MAX_FILTER_TAGS:
        raise Refusal(Result.RESULT_OPERATION_FAILED, f'tags filter has '
                      f'{len(tags_filter.tags)} tags, more than {MAX_FILTER_TAGS}')
    mode = tags_filter.filter_mode
    if mode not in (TagsFilter.FILTER_MODE_ANY, TagsFilter.FILTER_MODE_ALL):
        raise Refusal(Result.RESULT_OPERATION_FAILED, f'tags filter mode {mode} is neither '
                      f'FILTER_MODE_ANY ({TagsFilter.FILTER_MODE_ANY}) nor FILTER_MODE_ALL '
                      f'({TagsFilter.FILTER_MODE_ALL})')
    if not wanted:
        return None
    if mode == TagsFilter.FILTER_MODE_ALL:
        return wanted.issubset
    return lambda tags: not wanted.isdisjoint(tags)


def _bounds_test(message):
    """Return a test of OrientedBoxes against the bounds of a filter, None for no bounds."""
    kind = message.type
    if kind == Bounds.TYPE_EMPTY:
        return None
    if kind not in (Bounds.TYPE_SPHERE, Bounds.TYPE_BOX, Bounds.TYPE_CONVEX_HULL):
        raise Refusal(Result.RESULT_FEATURE_UNSUPPORTED, f'bounds type {kind} is none of '
                      f'TYPE_EMPTY, TYPE_BOX, TYPE_CONVEX_HULL, TYPE_SPHERE')
    points = bounds_points(message)
    if kind == Bounds.TYPE_SPHERE:
        if len(points) != 2:
            raise _bad_bounds(f'a sphere has 2 points (centre, then radius, 0, 0), not '
                              f'{len(points)}')
        radius = points[1][0]
        if not radius > 0.0:
            raise _bad_bounds(f'sphere radius must be positive: {radius}')
        return lambda boxes: bounds.overlaps_sphere(boxes, points[0], radius)
    if kind == Bounds.TYPE_BOX:
        if len(points) != 2:
            raise _bad_bounds(f'a box has 2 points (opposite corners), not {len(points)}')
        lower, upper = points.min(axis=0), points.max(axis=0)
        return lambda boxes: bounds.overlaps_box(boxes, lower, upper)
    if len(points) < 3 or np.linalg.matrix_rank(points - points[0], tol=1e-9) < 2:
        raise _bad_bounds(f'a convex hull needs at least 3 points not on one line; '
                          f'{len(points)} given')
    return lambda boxes: bounds.overlaps_hull(boxes, points)


def bounds_points(message):
    """Return the points of a Bounds message as an (n, 3) array, refusing NaN and too many."""
    if len(message.points) > MAX_HULL_POINTS:
        raise _bad_bounds(f'{len(message.points)} points are more than {MAX_HULL_POINTS}')
    points = np.array([(point.x, point.y, point.z) for point in message.points],
                      dtype=float).reshape(-1, 3)
    if not np.isfinite(points).all():
        bad = next(index for index, row in enumerate(points.tolist())
                   if not all(math.isfinite(value) for value in row))
        raise _bad_bounds(f'point {bad} is not finite: {points[bad].tolist()}')
    return points


def _bad_bounds(reason):
    return Refusal(Result.RESULT_OPERATION_FAILED, f'bounds: {reason}')
