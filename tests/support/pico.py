"""The emulated Raspberry Pi Pico (texelpad.sim.emulated: rp2040js running
the real MicroPython v1.28 firmware, from ../shared/instruments/rp2emu) for
tests: a context manager that skips when this machine cannot run it, and a
module-scoped fixture (one emulator per test module: everything on it runs
~3x slower than on a chip).

    from support.pico import pico        # noqa: F401 (a fixture)

    def test_x(pico): ... pico.port ...
"""
from __future__ import annotations

import os
from contextlib import contextmanager
from typing import Iterator

import pytest

from texelpad.sim.emulated import EmulatedPico, group_members, why_not  # noqa: F401


def processes_mentioning(text: str) -> list[tuple[int, str]]:
    """(pid, command line) of every live process whose command line holds text."""
    out = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open("/proc/%s/cmdline" % entry, "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode("utf-8", "replace")
            with open("/proc/%s/stat" % entry, "rb") as f:
                stat = f.read().decode("ascii", "replace")
        except OSError:
            continue
        if text in cmd and stat[stat.rindex(")") + 2:].split()[0] != "Z":
            out.append((int(entry), cmd.strip()))
    return out


@contextmanager
def emulated_pico(extra_args: tuple[str, ...] = (),
                  firmware: str | os.PathLike | None = None) -> Iterator[EmulatedPico]:
    """A fresh emulated Pico on a pty (an empty temporary flash), stopped on
    the way out whatever happened (no process or folder left); pytest.skip
    when this machine cannot run it (no instruments, no node). firmware: a
    .uf2 booted as if dragged onto it (the texelpad firmware), else the
    instrument's stock MicroPython. .notes is the tests' own bookkeeping
    (e.g. whether it was deployed)."""
    why = why_not()
    if why:
        pytest.skip(why)
    emu = EmulatedPico(extra_args=extra_args, firmware=firmware)
    emu.notes = {}
    try:
        emu.start()
        yield emu
    finally:
        summary = emu.stop()
        if summary.strip():
            print("[emulated Pico] " + " ".join(summary.split()))


@pytest.fixture(scope="module")
def pico() -> Iterator[EmulatedPico]:
    """One fresh emulated Pico for the whole test module (nothing deployed)."""
    with emulated_pico() as emu:
        yield emu
