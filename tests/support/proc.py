"""Stopping an instrument started in a process group of its own (start_new_session=True): the
emulated STM32 (tests/support/stm32.py) and the emulated CircuitPython Pico
(tests/host/test_emulated_cpy.py) - their run.sh stops QEMU or node on SIGTERM."""
from __future__ import annotations

import os
import signal
import subprocess


def stop_group(proc: subprocess.Popen, grace: float = 15.0) -> None:
    """SIGTERM the process group, SIGKILL it after `grace` seconds; reap it."""
    try:
        os.killpg(proc.pid, signal.SIGTERM)
    except ProcessLookupError:
        pass
    try:
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
