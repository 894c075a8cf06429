"""The standard's Result: how every service of simulation_interfaces says what happened."""

from service_tutorial.sim.validation import WorldError
from simulation_interfaces.msg import Result


class Refusal(Exception):
    """A request the standard answers with a code of its own and a message naming the value."""

    def __init__(self, code, message):
        super().__init__(message)
        self.code = code


def answer(node, service, result, operation):
    """
    Run operation and write its outcome into result (a simulation_interfaces Result).

    A Refusal gives its code, a WorldError (the core refusing) RESULT_OPERATION_FAILED; any
    other exception is a bug, answered as a failed operation rather than taking the world down.
    Returns what operation returned, or None when it failed.
    """
    try:
        value = operation()
    except Refusal as refusal:
        return _failed(node, service, result, refusal.code, str(refusal), warn=True)
    except WorldError as error:
        return _failed(node, service, result, Result.RESULT_OPERATION_FAILED, str(error),
                       warn=True)
    except Exception as error:  # a bug must not take the world down with it
        return _failed(node, service, result, Result.RESULT_OPERATION_FAILED,
                       f'internal error: {error!r}', warn=False)
    result.result = Result.RESULT_OK
    result.error_message = ''
    return value


def _failed(node, service, result, code, message, *, warn):
    result.result = code
    result.error_message = f'{service}: {message}'
    log = node.get_logger().warning if warn else node.get_logger().error
    log(result.error_message)
    return None
