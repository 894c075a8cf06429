"""What the two turning clients make of typed input, without ROS: values, prompts, arguments."""

from types import SimpleNamespace

from programs import run_program
import pytest
from service_tutorial.lesson import robot_turning_action_client as action_client
from service_tutorial.lesson import robot_turning_client as service_client
from service_tutorial.lesson.robot_turning_action_client import ANGLE_PROMPT, ANGLE_TOO_LARGE
from service_tutorial.lesson.robot_turning_action_client import ask_turning_goal
from service_tutorial.lesson.robot_turning_action_client import parse_turning_goal
from service_tutorial.lesson.robot_turning_action_client import VELOCITY_NOT_POSITIVE
from service_tutorial.lesson.turning_input import ask_turning_request, DURATION_NOT_WHOLE
from service_tutorial.lesson.turning_input import DURATION_PROMPT, NOT_A_NUMBER
from service_tutorial.lesson.turning_input import parse_turning_request, TurningInputError
from service_tutorial.lesson.turning_input import VELOCITY_PROMPT, VELOCITY_TOO_HIGH

CLIENTS = ('robot_turning_client', 'robot_turning_action_client')
# client: (its prompting, what is typed, the pair it takes, the errors logged, the prompts shown)
PROMPTING = {
    'robot_turning_client': (
        ask_turning_request, ['abc', '0.5', '2', '2.0', '2', '0.5'], (2, 0.5),
        [NOT_A_NUMBER, VELOCITY_TOO_HIGH], [DURATION_PROMPT, VELOCITY_PROMPT] * 3),
    'robot_turning_action_client': (
        ask_turning_goal, ['abc', '0.5', '1', '2.0', '1', '0', '1.5708', '0.5'], (1.5708, 0.5),
        [NOT_A_NUMBER, VELOCITY_TOO_HIGH, VELOCITY_NOT_POSITIVE],
        [ANGLE_PROMPT, VELOCITY_PROMPT] * 4),
}
# client: (its command line, the field it fills, arguments it takes and the pair, ones refused)
ARGUMENTS = {
    'robot_turning_client': (
        service_client.parse_arguments, 'request',
        {('2', '0.5'): (2, 0.5), ('1', '-0.3'): (1, -0.3)},
        [['2'], ['2', '3.0'], ['x', '0.5']]),
    'robot_turning_action_client': (
        action_client.parse_arguments, 'goal',
        {('1.5708', '0.5'): (1.5708, 0.5), ('-1.5708', '0.5'): (-1.5708, 0.5)},
        [['1'], ['1', '3.0'], ['x', '0.5'], ['1', '0'], ['1000', '0.5']]),
}


@pytest.mark.parametrize('duration, velocity, expected', [
    ('2', '0.5', (2, 0.5)),
    (' 3 ', '-1.5707', (3, -1.5707)),
    ('0', '0', (0, 0.0)),
    ('5.0', '1', (5, 1.0)),
])
def test_valid_input_becomes_a_request(duration, velocity, expected):
    assert parse_turning_request(duration, velocity) == expected


@pytest.mark.parametrize('duration, velocity, message', [
    ('abc', '0.5', NOT_A_NUMBER),
    ('2', 'fast', NOT_A_NUMBER),
    ('', '', NOT_A_NUMBER),
    ('2', 'nan', NOT_A_NUMBER),
    ('inf', '0.5', NOT_A_NUMBER),
    ('2', '2.0', VELOCITY_TOO_HIGH),
    ('2', '-1.6', VELOCITY_TOO_HIGH),
    ('-1', '0.5', DURATION_NOT_WHOLE),
    ('1.5', '0.5', DURATION_NOT_WHOLE),
    ('5000000000', '0.5', DURATION_NOT_WHOLE),
])
def test_invalid_input_is_refused_with_the_lessons_message(duration, velocity, message):
    with pytest.raises(TurningInputError, match=message.replace('!', '\\!')):
        parse_turning_request(duration, velocity)


@pytest.mark.parametrize('angle, velocity, expected', [
    ('1.5708', '0.5', (1.5708, 0.5)),
    (' -3 ', '1.5707', (-3.0, 1.5707)),
    ('0', '0.1', (0.0, 0.1)),
    ('-62.83', '1', (-62.83, 1.0)),
])
def test_valid_input_becomes_a_goal(angle, velocity, expected):
    assert parse_turning_goal(angle, velocity) == expected


@pytest.mark.parametrize('angle, velocity, message', [
    ('abc', '0.5', NOT_A_NUMBER),
    ('1', 'fast', NOT_A_NUMBER),
    ('', '', NOT_A_NUMBER),
    ('nan', '0.5', NOT_A_NUMBER),
    ('1', 'inf', NOT_A_NUMBER),
    ('1', '2.0', VELOCITY_TOO_HIGH),
    ('1', '1.5708', VELOCITY_TOO_HIGH),
    ('1', '0', VELOCITY_NOT_POSITIVE),
    ('1', '-0.5', VELOCITY_NOT_POSITIVE),
    ('100', '0.5', ANGLE_TOO_LARGE),
    ('-62.9', '0.5', ANGLE_TOO_LARGE),
])
def test_invalid_goal_input_is_refused_like_the_lessons_client(angle, velocity, message):
    with pytest.raises(TurningInputError) as error:
        parse_turning_goal(angle, velocity)
    assert str(error.value) == message


@pytest.mark.parametrize('client', CLIENTS)
def test_prompts_again_until_a_valid_pair_is_typed(client):
    ask, typed, taken, logged, shown = PROMPTING[client]
    answers = iter(typed + ['never read', 'never read'])
    prompts, errors = [], []

    def read(prompt):
        prompts.append(prompt)
        return next(answers)

    # A node's logger, keeping the errors.
    assert ask(SimpleNamespace(error=errors.append), read=read) == taken
    assert errors == logged
    assert prompts == shown


@pytest.mark.parametrize('client', CLIENTS)
def test_end_of_input_ends_the_prompting(client):
    def read(prompt):
        raise EOFError

    with pytest.raises(EOFError):
        PROMPTING[client][0](SimpleNamespace(error=[].append), read=read)


@pytest.mark.parametrize('client', CLIENTS)
def test_arguments_give_the_pair_without_prompting(client):
    parse, field, taken, refused = ARGUMENTS[client]
    for arguments, pair in taken.items():
        assert getattr(parse(list(arguments)), field) == pair
    assert getattr(parse([]), field) is None
    for wrong in refused:
        with pytest.raises(SystemExit) as exit_info:
            parse(wrong)
        assert exit_info.value.code == 2


@pytest.mark.parametrize('client', CLIENTS)
def test_help_and_end_of_input_need_no_ros_graph(client):
    assert 'angular_vel' in run_program(client, '--help', stdin='').stdout

    finished = run_program(client, stdin='')

    assert finished.returncode == 1
    assert 'Traceback' not in finished.stderr
