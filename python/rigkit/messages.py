"""The rig's driver messages (docs/driver.md) as ctypes structures, for iceoryx2's
Python bindings: `node.service_builder(name).publish_subscribe(DriverSample)`.

The `type_name()` of each class is the identity iceoryx2 checks across processes and
languages (with the size and alignment), so it must be exactly the Rust crate's
`#[type_name]`. This module only needs ctypes; the rig's tests compare its layouts with
the Rust structs.
"""

import ctypes

MAX_X = 8
MAX_U = 4
VERSION = 3

# status bits of DriverSample.status
READY = 1
RESETTING = 2
WATCHDOG = 4
# DriverCommand.kind
ACTION = 1
RESET = 2
# DriverInfo.provides bits
PROVIDES_REWARD = 1
# DriverSample.ending bits (with PROVIDES_REWARD)
TERMINATED = 1
TRUNCATED = 2
# DriverInfo.clock
REALTIME = 0
LOCKSTEP = 1


class DriverInfo(ctypes.Structure):
    """rig.DriverInfo.v3 (docs/driver.md)."""

    _fields_ = [
        ("version", ctypes.c_uint64),
        ("task", ctypes.c_char * 32),
        ("task_hash", ctypes.c_uint64),
        ("clock", ctypes.c_uint64),
        ("n_x", ctypes.c_uint64),
        ("n_u", ctypes.c_uint64),
        ("period_ns", ctypes.c_uint64),
        ("time_scale", ctypes.c_double),
        ("u_min", ctypes.c_double * MAX_U),
        ("u_max", ctypes.c_double * MAX_U),
        ("watchdog_periods", ctypes.c_uint64),
        ("t_start_ns", ctypes.c_uint64),
        ("t_publish_ns", ctypes.c_uint64),
        ("provides", ctypes.c_uint64),
    ]

    @staticmethod
    def type_name() -> str:
        return "rig.DriverInfo.v3"


class DriverSample(ctypes.Structure):
    """rig.DriverSample.v2 (docs/driver.md)."""

    _fields_ = [
        ("seq", ctypes.c_uint64),
        ("t_sample_ns", ctypes.c_uint64),
        ("t_publish_ns", ctypes.c_uint64),
        ("status", ctypes.c_uint64),
        ("reset_id", ctypes.c_uint64),
        ("last_command", ctypes.c_uint64),
        ("n_x", ctypes.c_uint64),
        ("n_u", ctypes.c_uint64),
        ("x", ctypes.c_double * MAX_X),
        ("u_applied", ctypes.c_double * MAX_U),
        ("clamped", ctypes.c_uint64),
        ("rejected", ctypes.c_uint64),
        ("watchdog_trips", ctypes.c_uint64),
        ("reward", ctypes.c_double),
        ("ending", ctypes.c_uint64),
    ]

    @staticmethod
    def type_name() -> str:
        return "rig.DriverSample.v2"


class DriverCommand(ctypes.Structure):
    """rig.DriverCommand.v1 (docs/driver.md)."""

    _fields_ = [
        ("seq", ctypes.c_uint64),
        ("kind", ctypes.c_uint64),
        ("sample_seq", ctypes.c_uint64),
        ("t_publish_ns", ctypes.c_uint64),
        ("n_u", ctypes.c_uint64),
        ("u", ctypes.c_double * MAX_U),
        ("n_x", ctypes.c_uint64),
        ("x0", ctypes.c_double * MAX_X),
    ]

    @staticmethod
    def type_name() -> str:
        return "rig.DriverCommand.v1"
