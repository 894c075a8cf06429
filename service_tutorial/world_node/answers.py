"""
The one adapter from the world's refusals to answers, in both dialects the node speaks.

The core refuses with a WorldError that carries its Reason (sim/validation.py); a service
refuses what only it can judge (a request's own limits) with a Refusal and the standard's code.
Here either becomes the standard's Result, a code and a message, or the lesson's success and
status_message as gazebo_ros answers them: the same words after the service's name, so a bad
request reads the same whichever way it came. Any other exception is a bug, answered as a
failed operation rather than taking the world down.
"""

from service_tutorial.sim.validation import Reason, WorldError
from simulation_interfaces.msg import Result, SpawnResult
from simulation_interfaces.srv import LoadWorld

# The standard's code for each reason, where a service has one of its own; any other reason is
# RESULT_OPERATION_FAILED.
STANDARD_CODES = {Reason.NO_SUCH_MODEL: Result.RESULT_NOT_FOUND}
SPAWN_CODES = {
    **STANDARD_CODES,
    Reason.NAME_INVALID: SpawnResult.NAME_INVALID,
    Reason.NAME_TAKEN: SpawnResult.NAME_NOT_UNIQUE,
    Reason.NAMESPACE_INVALID: SpawnResult.NAMESPACE_INVALID,
    Reason.UNKNOWN_FRAME: SpawnResult.INVALID_POSE,
    Reason.BAD_POSE: SpawnResult.INVALID_POSE,
    Reason.NO_RESOURCE: SpawnResult.NO_RESOURCE,
    Reason.UNSUPPORTED_FORMAT: SpawnResult.UNSUPPORTED_FORMAT,
    Reason.NOT_PARSEABLE: SpawnResult.RESOURCE_PARSE_ERROR,
    Reason.DOES_NOT_COMPILE: SpawnResult.RESOURCE_PARSE_ERROR,
    Reason.MISSING_ASSET: SpawnResult.MISSING_ASSETS,
    Reason.REFUSED_ASSET: SpawnResult.UNSUPPORTED_ASSETS,
    Reason.UNSUPPORTED_CONTENT: SpawnResult.UNSUPPORTED_ASSETS,
}
LOAD_WORLD_CODES = {
    Reason.NO_RESOURCE: LoadWorld.Response.NO_RESOURCE,
    Reason.UNSUPPORTED_FORMAT: LoadWorld.Response.UNSUPPORTED_FORMAT,
    Reason.NOT_PARSEABLE: LoadWorld.Response.RESOURCE_PARSE_ERROR,
    Reason.DOES_NOT_COMPILE: LoadWorld.Response.RESOURCE_PARSE_ERROR,
    Reason.MISSING_ASSET: LoadWorld.Response.MISSING_ASSETS,
    Reason.REFUSED_ASSET: LoadWorld.Response.UNSUPPORTED_ASSETS,
    Reason.UNSUPPORTED_CONTENT: LoadWorld.Response.UNSUPPORTED_ASSETS,
}


class Refusal(Exception):
    """A request a service refuses itself, with the standard's code and a message."""

    def __init__(self, code, message):
        """Refuse with the standard's code and a message naming the value."""
        super().__init__(message)
        self.code = code


def standard_answer(node, service, result, operation, codes=STANDARD_CODES):
    """
    Run operation and write its outcome into result (a simulation_interfaces Result).

    codes: the service's code for each Reason of a WorldError. Return what operation returned,
    or None when it failed.
    """
    try:
        value = operation()
    except Refusal as refusal:
        return _refused(node, service, result, refusal.code, refusal)
    except WorldError as error:
        return _refused(node, service, result,
                        codes.get(error.reason, Result.RESULT_OPERATION_FAILED), error)
    except Exception as error:  # a bug must not take the world down with it
        return _refused(node, service, result, Result.RESULT_OPERATION_FAILED, error, bug=True)
    result.result = Result.RESULT_OK
    result.error_message = ''
    return value


def lesson_answer(node, service, response, operation):
    """Run operation and write its outcome (a status message) into the lesson's response."""
    try:
        response.status_message = operation()
        response.success = True
    except WorldError as error:
        response.success = False
        response.status_message = _logged(node, service, error, bug=False)
    except Exception as error:  # a bug must not take the world down with it
        response.success = False
        response.status_message = _logged(node, service, error, bug=True)
    return response


def raise_refusal(outcome):
    """Return a spawn's outcome, or raise it if it is the exception that refused the spawn."""
    if isinstance(outcome, Exception):
        raise outcome
    return outcome


def _refused(node, service, result, code, error, *, bug=False):
    result.result = code
    result.error_message = _logged(node, service, error, bug=bug)
    return None


def _logged(node, service, error, *, bug):
    """Return the message that answers an error, logged as a warning, or an error if a bug."""
    if bug:
        message = f'{service}: internal error: {error!r}'
        node.get_logger().error(message)
    else:
        message = f'{service}: {error}'
        node.get_logger().warning(message)
    return message
