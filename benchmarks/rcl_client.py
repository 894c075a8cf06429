"""
A service client in C, through librcl and ctypes: the client side of a call as C or C++ pays it.

rclpy's client turns every answer into Python message objects, which for a large answer (50
nested EntityState messages) costs the client more than the server's whole work; a C or C++
client reads the same bytes into C structs in microseconds. A benchmark that holds a service
to the server's cost calls it through RclClient instead: an rcl client on the rcl node of an
rclpy node, the service's C type support and C structs (rosidl_typesupport_c,
rosidl_generator_c), the request sent with rcl_send_request and the answer waited for in an
rcl wait set and taken with rcl_take_response. ctypes releases the GIL around every C call,
so the wait leaves Python free for the executors of this process.

The structs below follow the Jazzy headers (rcl/client.h, rcl/wait.h, rmw/types.h,
rcutils/allocator.h, rosidl_runtime_c/string.h).
"""

import ctypes
import ctypes.util
import functools
import os
import time

from harness import BenchmarkError

RCL_RET_OK = 0
RCL_RET_TIMEOUT = 2
RCL_RET_CLIENT_TAKE_FAILED = 501
RMW_GID_STORAGE_SIZE = 16
ERROR_MESSAGE_MAX_LENGTH = 1024  # RCUTILS_ERROR_MESSAGE_MAX_LENGTH
RET = ctypes.c_int32  # rcl_ret_t


class Allocator(ctypes.Structure):
    """rcutils_allocator_t (rcl_allocator_t): four functions and their state."""

    _fields_ = [('allocate', ctypes.c_void_p), ('deallocate', ctypes.c_void_p),
                ('reallocate', ctypes.c_void_p), ('zero_allocate', ctypes.c_void_p),
                ('state', ctypes.c_void_p)]


class RmwTime(ctypes.Structure):
    """rmw_time_t."""

    _fields_ = [('sec', ctypes.c_uint64), ('nsec', ctypes.c_uint64)]


class QosProfile(ctypes.Structure):
    """rmw_qos_profile_t; its policies are C enums (int)."""

    _fields_ = [('history', ctypes.c_int), ('depth', ctypes.c_size_t),
                ('reliability', ctypes.c_int), ('durability', ctypes.c_int),
                ('deadline', RmwTime), ('lifespan', RmwTime), ('liveliness', ctypes.c_int),
                ('liveliness_lease_duration', RmwTime),
                ('avoid_ros_namespace_conventions', ctypes.c_bool)]


class ClientOptions(ctypes.Structure):
    """rcl_client_options_t."""

    _fields_ = [('qos', QosProfile), ('allocator', Allocator)]


class Client(ctypes.Structure):
    """rcl_client_t; zero-initialised as rcl_get_zero_initialized_client() makes it."""

    _fields_ = [('impl', ctypes.c_void_p)]


class WaitSet(ctypes.Structure):
    """rcl_wait_set_t; zero-initialised as rcl_get_zero_initialized_wait_set() makes it."""

    _fields_ = [field for kind in ('subscriptions', 'guard_conditions', 'timers', 'clients',
                                   'services', 'events')
                for field in ((kind, ctypes.POINTER(ctypes.c_void_p)),
                              (f'size_of_{kind}', ctypes.c_size_t))] + [
        ('impl', ctypes.c_void_p)]


class RequestId(ctypes.Structure):
    """rmw_request_id_t: which request an answer is to."""

    _fields_ = [('writer_guid', ctypes.c_uint8 * RMW_GID_STORAGE_SIZE),
                ('sequence_number', ctypes.c_int64)]


class ErrorString(ctypes.Structure):
    """rcutils_error_string_t."""

    _fields_ = [('str', ctypes.c_char * ERROR_MESSAGE_MAX_LENGTH)]


class String(ctypes.Structure):
    """rosidl_runtime_c__String, a string field of a C message."""

    _fields_ = [('data', ctypes.c_char_p), ('size', ctypes.c_size_t),
                ('capacity', ctypes.c_size_t)]


class Sequence(ctypes.Structure):
    """A sequence field of a C message (<type>__Sequence): its items and how many."""

    _fields_ = [('data', ctypes.c_void_p), ('size', ctypes.c_size_t),
                ('capacity', ctypes.c_size_t)]


def load_library(name):
    """Load lib<name>.so from the lib folder of a ROS prefix, else where the loader finds it."""
    for prefix in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep):
        path = os.path.join(prefix, 'lib', f'lib{name}.so')
        if prefix and os.path.isfile(path):
            return ctypes.CDLL(path)
    found = ctypes.util.find_library(name)
    if found is None:
        raise BenchmarkError(f'lib{name}.so is in no lib folder of AMENT_PREFIX_PATH nor '
                             'where the loader looks')
    return ctypes.CDLL(found)


def _declare(library, name, restype, *argtypes):
    function = getattr(library, name)
    function.restype, function.argtypes = restype, list(argtypes)
    return function


class _Rcl:
    """The functions of librcl and librcutils this client calls, declared once."""

    def __init__(self):
        rcl, rcutils = load_library('rcl'), load_library('rcutils')
        client, wait_set = ctypes.POINTER(Client), ctypes.POINTER(WaitSet)
        size = ctypes.c_size_t
        self.client_get_default_options = _declare(rcl, 'rcl_client_get_default_options',
                                                   ClientOptions)
        self.client_init = _declare(rcl, 'rcl_client_init', RET, client, ctypes.c_void_p,
                                    ctypes.c_void_p, ctypes.c_char_p,
                                    ctypes.POINTER(ClientOptions))
        self.client_fini = _declare(rcl, 'rcl_client_fini', RET, client, ctypes.c_void_p)
        self.server_is_available = _declare(rcl, 'rcl_service_server_is_available', RET,
                                            ctypes.c_void_p, client,
                                            ctypes.POINTER(ctypes.c_bool))
        self.send_request = _declare(rcl, 'rcl_send_request', RET, client, ctypes.c_void_p,
                                     ctypes.POINTER(ctypes.c_int64))
        self.take_response = _declare(rcl, 'rcl_take_response', RET, client,
                                      ctypes.POINTER(RequestId), ctypes.c_void_p)
        self.wait_set_init = _declare(rcl, 'rcl_wait_set_init', RET, wait_set, size, size, size,
                                      size, size, size, ctypes.c_void_p, Allocator)
        self.wait_set_clear = _declare(rcl, 'rcl_wait_set_clear', RET, wait_set)
        self.wait_set_add_client = _declare(rcl, 'rcl_wait_set_add_client', RET, wait_set,
                                            client, ctypes.POINTER(size))
        self.wait = _declare(rcl, 'rcl_wait', RET, wait_set, ctypes.c_int64)
        self.wait_set_fini = _declare(rcl, 'rcl_wait_set_fini', RET, wait_set)
        self.default_allocator = _declare(rcutils, 'rcutils_get_default_allocator', Allocator)
        self._error_string = _declare(rcutils, 'rcutils_get_error_string', ErrorString)
        self._reset_error = _declare(rcutils, 'rcutils_reset_error', None)

    def check(self, ret, what):
        """Raise BenchmarkError with rcl's error message unless ret is RCL_RET_OK."""
        if ret != RCL_RET_OK:
            message = self._error_string().str.decode(errors='replace')
            self._reset_error()
            raise BenchmarkError(f'{what} failed ({ret}): {message}')


@functools.lru_cache(maxsize=None)
def _functions():
    """Return the functions of librcl and librcutils, declared on first use."""
    return _Rcl()


class RclClient:
    """
    A client in C of one service, on an rclpy node's rcl node; it sends the default request.

    call() leaves the answer in a C struct of the service's Response type, valid until the
    next call; response(layout) reads it through a ctypes Structure of that layout.
    """

    def __init__(self, node, srv_type, service_name):
        """Make the client of srv_type (an rclpy service class) for service_name on node."""
        rcl = self._rcl = _functions()
        package = srv_type.__module__.split('.')[0]  # simulation_interfaces.srv._get_...
        c_name = f'{package}__srv__{srv_type.__name__}'
        support = _declare(load_library(f'{package}__rosidl_typesupport_c'),
                           f'rosidl_typesupport_c__get_service_type_support_handle__{c_name}',
                           ctypes.c_void_p)
        structs = load_library(f'{package}__rosidl_generator_c')
        self._destroy_request = _declare(structs, f'{c_name}_Request__destroy', None,
                                         ctypes.c_void_p)
        self._destroy_response = _declare(structs, f'{c_name}_Response__destroy', None,
                                          ctypes.c_void_p)
        self._node = node  # keeps the rcl node alive as long as the client
        self._rcl_node = ctypes.c_void_p(node.handle.pointer)
        self.name = service_name
        self._request = _declare(structs, f'{c_name}_Request__create', ctypes.c_void_p)()
        self._response = _declare(structs, f'{c_name}_Response__create', ctypes.c_void_p)()
        self._client, self._wait_set = Client(), WaitSet()
        if not self._request or not self._response:
            self.destroy()
            raise BenchmarkError(f'could not allocate the C messages of {c_name}')
        options = rcl.client_get_default_options()
        try:
            rcl.check(rcl.client_init(ctypes.byref(self._client), self._rcl_node, support(),
                                      service_name.encode(), ctypes.byref(options)),
                      f'rcl_client_init of {service_name}')
            # rcl_node_t starts with its rcl_context_t pointer (rcl/node.h).
            context = ctypes.cast(self._rcl_node, ctypes.POINTER(ctypes.c_void_p))[0]
            rcl.check(rcl.wait_set_init(ctypes.byref(self._wait_set), 0, 0, 0, 1, 0, 0,
                                        context, rcl.default_allocator()),
                      'rcl_wait_set_init')
        except BenchmarkError:
            self.destroy()
            raise

    def wait_for_service(self, *, timeout=30.0):
        """Wait until the service has a server; raise BenchmarkError after timeout s."""
        available, deadline = ctypes.c_bool(False), time.monotonic() + timeout
        while True:
            self._rcl.check(self._rcl.server_is_available(
                self._rcl_node, ctypes.byref(self._client), ctypes.byref(available)),
                'rcl_service_server_is_available')
            if available.value:
                return
            if time.monotonic() > deadline:
                raise BenchmarkError(f'service {self.name} did not appear within {timeout} s')
            time.sleep(0.002)

    def call(self, *, timeout=30.0):
        """Send the request and wait for its answer, left in the response struct."""
        rcl = self._rcl
        sequence_number, header = ctypes.c_int64(), RequestId()
        rcl.check(rcl.send_request(ctypes.byref(self._client), self._request,
                                   ctypes.byref(sequence_number)), f'request to {self.name}')
        deadline = time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0.0:
                raise BenchmarkError(f'service {self.name} did not answer within {timeout} s')
            rcl.check(rcl.wait_set_clear(ctypes.byref(self._wait_set)), 'rcl_wait_set_clear')
            rcl.check(rcl.wait_set_add_client(ctypes.byref(self._wait_set),
                                              ctypes.byref(self._client), None),
                      'rcl_wait_set_add_client')
            ret = rcl.wait(ctypes.byref(self._wait_set), int(left * 1e9))
            if ret == RCL_RET_TIMEOUT:
                continue
            rcl.check(ret, f'waiting for {self.name}')
            ret = rcl.take_response(ctypes.byref(self._client), ctypes.byref(header),
                                    self._response)
            if ret == RCL_RET_OK and header.sequence_number == sequence_number.value:
                return
            if ret != RCL_RET_CLIENT_TAKE_FAILED:  # an answer to an earlier call is dropped
                rcl.check(ret, f'taking the answer of {self.name}')

    def response(self, layout):
        """Return the last answer through layout, a ctypes Structure of the Response type."""
        return ctypes.cast(self._response, ctypes.POINTER(layout)).contents

    def destroy(self):
        """Destroy the wait set, the client and the C messages; before the node goes."""
        if self._wait_set.impl:
            self._rcl.wait_set_fini(ctypes.byref(self._wait_set))
        if self._client.impl:
            self._rcl.client_fini(ctypes.byref(self._client), self._rcl_node)
        if self._request:
            self._destroy_request(self._request)
            self._request = None
        if self._response:
            self._destroy_response(self._response)
            self._response = None
