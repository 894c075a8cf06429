"""
The standard's entity filters through the running world: names, categories, tags, bounds.

Every kind of filter picks the entities it should, all given filters apply together, and every
hostile filter (catastrophic patterns, NaN bounds, a million hull points) is answered with its
code within the time of a normal call, the world unchanged.
"""

from geometry_msgs.msg import Vector3
import pytest
from repository import read_model
from service_tutorial.world_node.answers import Refusal
from service_tutorial.world_node.standard.entity_filters import EntityFilter
from simulation_interfaces.msg import Bounds, EntityCategory, EntityFilters, EntityInfo
from simulation_interfaces.msg import Result, TagsFilter
from simulation_interfaces.srv import GetEntitiesStates, SetEntityInfo
from standard_entities import close, CRATE, entities, red_box, snapshot, spawn_or_fail
from standard_entities import stamped

pytestmark = pytest.mark.ros

ROBOT = EntityCategory.CATEGORY_ROBOT
OBJECT = EntityCategory.CATEGORY_OBJECT
STATIC = EntityCategory.CATEGORY_STATIC_OBJECT
LONG_NAME = 'a' * 64


@pytest.fixture(scope='class')
def yard(class_ros):
    """Start a paused world: tinybot at the origin, scout at (5, 5), a crate, a red box..."""
    world = class_ros.start_world(paused=True, real_time_factor=0.0)
    spawn_or_fail(world, name='scout', resource_string=read_model('tinybot'),
                  initial_pose=stamped(5.0, 5.0, 0.0))
    spawn_or_fail(world, name='crate', resource_string=CRATE, initial_pose=stamped(-3.0, 0, 0.2))
    spawn_or_fail(world, name='red_box', resource_string=red_box(),
                  initial_pose=stamped(0.0, -4.0))
    spawn_or_fail(world, name=LONG_NAME, resource_string=CRATE, initial_pose=stamped(0, 8, 0.2))
    for name, tags in (('tinybot', ['wheeled', 'lesson']), ('scout', ['wheeled', 'patrol']),
                       ('crate', ['cargo'])):
        info = EntityInfo(category=EntityCategory(category=ROBOT if name != 'crate' else OBJECT),
                          tags=tags)
        answer = world.call(SetEntityInfo, '/set_entity_info',
                            SetEntityInfo.Request(entity=name, info=info))
        assert answer.result.result == Result.RESULT_OK
    return world


class Unwalkable(list):
    """A list that notes when its items are walked or picked; its len() is free to take."""

    walked = True

    def __iter__(self):
        self.walked = True
        return super().__iter__()

    def __getitem__(self, index):
        self.walked = True
        return super().__getitem__(index)


def points(*coordinates):
    """Return Vector3 messages of (x, y, z) triples."""
    return [Vector3(x=float(x), y=float(y), z=float(z)) for x, y, z in coordinates]


def picked(world, **filters):
    """Return the names GetEntities gives for an EntityFilters built of keyword fields."""
    answer = entities(world, EntityFilters(**filters))
    assert answer.result.result == Result.RESULT_OK, answer.result.error_message
    return answer.entities


def refusal(world, **filters):
    """Return (code, message) of a GetEntities call that must be refused, within its timeout."""
    answer = entities(world, EntityFilters(**filters))
    assert answer.result.result != Result.RESULT_OK
    return answer.result.result, answer.result.error_message


class TestFilters:
    """Each kind of filter on one yard of entities."""

    def test_no_filter_lists_every_entity_in_spawn_order(self, yard):
        assert picked(yard) == ['tinybot', 'scout', 'crate', 'red_box', LONG_NAME]

    def test_name_patterns_are_posix_extended_regular_expressions(self, yard):
        assert picked(yard, filter='^(tiny|sc)') == ['tinybot', 'scout']
        assert picked(yard, filter='bo') == ['tinybot', 'red_box']
        assert picked(yard, filter='^[[:alpha:]]+$') == ['tinybot', 'scout', 'crate',
                                                         LONG_NAME]
        assert picked(yard, filter='_') == ['red_box']
        assert picked(yard, filter='^a{64}$') == [LONG_NAME]

    def test_categories_match_any_of_them(self, yard):
        category = EntityCategory
        assert picked(yard, categories=[category(category=STATIC)]) == ['red_box']
        assert picked(yard, categories=[category(category=OBJECT), category(category=STATIC)]) \
            == ['crate', 'red_box', LONG_NAME]

    def test_tags_any_and_all(self, yard):
        any_mode = TagsFilter(tags=['lesson', 'cargo'], filter_mode=TagsFilter.FILTER_MODE_ANY)
        all_mode = TagsFilter(tags=['wheeled', 'patrol'], filter_mode=TagsFilter.FILTER_MODE_ALL)
        assert picked(yard, tags=any_mode) == ['tinybot', 'crate']
        assert picked(yard, tags=all_mode) == ['scout']

    def test_a_sphere_box_and_hull_include_one_robot_and_exclude_the_other(self, yard):
        sphere = Bounds(type=Bounds.TYPE_SPHERE, points=points((5.0, 5.3, 0.05), (0.2, 0, 0)))
        box = Bounds(type=Bounds.TYPE_BOX, points=points((0.05, 0.05, 0.0), (-1.0, -1.0, 1.0)))
        hull = Bounds(type=Bounds.TYPE_CONVEX_HULL, points=points(
            (4.0, 4.0, 0.0), (6.0, 4.0, 0.0), (5.0, 6.0, 0.0), (5.0, 5.0, 1.0)))
        assert picked(yard, bounds=sphere) == ['scout']
        assert picked(yard, bounds=box) == ['tinybot']
        assert picked(yard, bounds=hull) == ['scout']
        # Just out of reach of scout's wheel (y up to 5.133).
        sphere.points = points((5.0, 5.4, 0.05), (0.2, 0, 0))
        assert picked(yard, bounds=sphere) == []

    def test_all_given_filters_apply_together(self, yard):
        wheeled = TagsFilter(tags=['wheeled'])
        near_origin = Bounds(type=Bounds.TYPE_SPHERE, points=points((0, 0, 0), (3.5, 0, 0)))
        assert picked(yard, filter='o', tags=wheeled) == ['tinybot', 'scout']
        assert picked(yard, filter='o', tags=wheeled, bounds=near_origin) == ['tinybot']

    def test_states_come_with_the_same_filters(self, yard):
        answer = yard.call(GetEntitiesStates, '/get_entities_states', GetEntitiesStates.Request(
            filters=EntityFilters(filter='^(scout|crate)$')))
        assert answer.result.result == Result.RESULT_OK
        assert answer.entities == ['scout', 'crate']
        scout, crate = answer.states
        position = scout.pose.position
        assert close((position.x, position.y, position.z), (5.0, 5.0, 0.0))
        assert scout.header.frame_id == 'world'

    def test_hostile_filters_are_refused_in_normal_time_and_change_nothing(self, yard):
        before = snapshot(yard)
        hull_points = points(*[(index, 0, 0) for index in range(3)])
        for filters, code, message in [
                ({'filter': '(?i)tiny'}, Result.RESULT_OPERATION_FAILED,
                 "name filter '(?i)tiny' is not a POSIX extended regular expression this world "
                 "runs: '(?' is not POSIX ERE syntax at position 1"),
                ({'filter': '\\d+'}, Result.RESULT_OPERATION_FAILED,
                 "'\\d' is not POSIX ERE syntax"),
                ({'filter': '(a'}, Result.RESULT_OPERATION_FAILED, "missing ')'"),
                ({'filter': 'x' * 100000}, Result.RESULT_OPERATION_FAILED,
                 'the pattern is 100000 characters long, more than 256'),
                ({'filter': '((a{1,255}){1,255})'}, Result.RESULT_OPERATION_FAILED,
                 'steps to run'),
                ({'tags': TagsFilter(tags=['x'], filter_mode=7)},
                 Result.RESULT_OPERATION_FAILED, 'tags filter mode 7 is neither'),
                ({'bounds': Bounds(type=9, points=points((0, 0, 0)))},
                 Result.RESULT_FEATURE_UNSUPPORTED, 'bounds type 9 is none of'),
                ({'bounds': Bounds(type=Bounds.TYPE_SPHERE, points=points(
                    (float('nan'), 0, 0), (1, 0, 0)))}, Result.RESULT_OPERATION_FAILED,
                 'bounds: point 0 is not finite: [nan, 0.0, 0.0]'),
                ({'bounds': Bounds(type=Bounds.TYPE_SPHERE,
                                   points=points((0, 0, 0), (0, 0, 0)))},
                 Result.RESULT_OPERATION_FAILED, 'bounds: sphere radius must be positive: 0.0'),
                ({'bounds': Bounds(type=Bounds.TYPE_BOX, points=points((0, 0, 0)))},
                 Result.RESULT_OPERATION_FAILED, 'a box has 2 points (opposite corners), not 1'),
                ({'bounds': Bounds(type=Bounds.TYPE_CONVEX_HULL, points=hull_points)},
                 Result.RESULT_OPERATION_FAILED,
                 'a convex hull needs at least 3 points not on one line; 3 given'),
                ({'bounds': Bounds(type=Bounds.TYPE_CONVEX_HULL, points=points(
                    *[(index % 7, index % 5, index % 3) for index in range(10001)]))},
                 Result.RESULT_OPERATION_FAILED, '10001 points are more than 10000')]:
            answer_code, answer_message = refusal(yard, **filters)
            assert answer_code == code, answer_message
            assert message in answer_message
        assert snapshot(yard) == before

    def test_a_catastrophic_pattern_on_a_long_name_takes_no_time(self, yard):
        # A backtracking matcher would take longer than the age of the universe on 64 letters;
        # the world answers within the call's timeout.
        for pattern in ('^(a*)*b$', '^(a|a)*b$', '^(a*){30}b$', '^(a+)+$'):
            names = picked(yard, filter=pattern)
            assert names == ([LONG_NAME] if pattern == '^(a+)+$' else [])

    def test_a_million_hull_points_are_refused(self, yard):
        points = Unwalkable([Vector3()] * 1_000_000)
        million = EntityFilters(bounds=Bounds(type=Bounds.TYPE_CONVEX_HULL, points=points))
        # The world's own check counts the points and looks at none of them; rclpy's turning
        # 24 MB into a million Vector3 objects before the callback runs takes seconds (see
        # docs/bad-input.md).
        points.walked = False
        with pytest.raises(Refusal, match='1000000 points are more than 10000'):
            EntityFilter(million, yard.node.world)
        assert not points.walked
        answer = entities(yard, million, timeout=120.0)
        assert answer.result.result == Result.RESULT_OPERATION_FAILED
        assert picked(yard, filter='^scout$') == ['scout']
