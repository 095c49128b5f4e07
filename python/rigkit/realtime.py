"""What a driver on real hardware needs of the machine (docs/driver.md): a driver id the
rig accepts, real-time scheduling, and the CPUs kept from deep idle states.

    check_driver_id(args.driver_id)        # ValueError: letters, digits, '-' and '_' only
    set_priority(10)                       # SCHED_FIFO 10 (CAP_SYS_NICE or root)
    limit = hold_cpu_wakeup_limit(0)       # while `limit` stays open (root)
    limit = timing(10, 0)                  # both, as --realtime-priority/--cpu-wakeup-us ask
"""

from __future__ import annotations

import os
import struct
from typing import BinaryIO

# The Linux PM QoS device whose open file holds the CPU wake-up latency limit.
CPU_DMA_LATENCY = "/dev/cpu_dma_latency"
MAX_WAKEUP_US = 2**31 - 1


def check_driver_id(driver_id: str) -> str:
    """`driver_id` if the rig's services can carry it (rig/driver/ID/...), else ValueError."""
    if not driver_id or not all(c.isascii() and (c.isalnum() or c in "-_") for c in driver_id):
        raise ValueError(f"{driver_id!r}: letters, digits, '-' and '_' only")
    return driver_id


def set_priority(priority: int) -> None:
    """This process on SCHED_FIFO at `priority` (1-99): on a loaded machine, normal
    scheduling wakes a driver milliseconds late now and then. OSError without
    CAP_SYS_NICE, ValueError for a priority out of range."""
    os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))


def hold_cpu_wakeup_limit(us: int) -> BinaryIO:
    """Holds the machine's CPU wake-up latency limit at `us` microseconds (0 keeps idle
    CPUs polling) for as long as the returned file stays open. OSError without root."""
    if not 0 <= us <= MAX_WAKEUP_US:
        raise ValueError(f"{us}: must be in [0, {MAX_WAKEUP_US}]")
    f = open(CPU_DMA_LATENCY, "wb", buffering=0)
    f.write(struct.pack("=i", us))
    return f


def timing(priority: int | None, wakeup_us: int | None) -> BinaryIO | None:
    """What `--realtime-priority N` and `--cpu-wakeup-us US` ask for, each if given: the
    open file holding the wake-up limit (None without one). RuntimeError in one line
    naming the flag and what it needs if either cannot be had."""
    if priority is not None:
        try:
            set_priority(priority)
        except (OSError, ValueError) as e:
            raise RuntimeError(
                f"--realtime-priority {priority}: {e} (needs CAP_SYS_NICE; priority 1-99)"
            ) from e
    if wakeup_us is None:
        return None
    try:
        return hold_cpu_wakeup_limit(wakeup_us)
    except OSError as e:
        raise RuntimeError(
            f"--cpu-wakeup-us {wakeup_us}: cannot hold the limit through {CPU_DMA_LATENCY}: {e} (needs root)"
        ) from e
