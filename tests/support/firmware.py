"""The texelpad firmware for tests: built once per test session with the offline kit
(../shared/instruments/mpfirmware) into a cache folder kept between runs (a rebuild of an
unchanged tree only relinks: seconds), and booted on the emulated Pico as if the .uf2 were
dragged onto it (texelpad.sim.emulated.EmulatedPico(firmware=...)).

Skips where the machine cannot build it (no arm-none-eabi-gcc, no kit) - except under CI
(CI=true), where .ci/run installs the toolchain: there a missing toolchain fails the test.
"""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from texelpad.image import cache_root


def why_not_build(port: str = "rp2") -> str | None:
    from texelpad import toolchain
    d = toolchain.instruments_dir()
    if port == "stm32":
        from texelpad.firmware.build_stm32 import kit_sources
        if kit_sources() is None:
            return "no stm32 MicroPython sources (../shared/instruments/stm32emu/micropython/src)"
    elif d is None or not (d / "mpfirmware" / "build.sh").is_file():
        return "no firmware kit (../shared/instruments/mpfirmware)"
    for t in (("arm-none-eabi-gcc", "make") if port == "stm32" else
              ("arm-none-eabi-gcc", "cmake", "make")):
        if not shutil.which(t):
            return ("%s not installed (Debian: gcc-arm-none-eabi libnewlib-arm-none-eabi cmake)"
                    % t)
    return None


def skip_or_fail(why: str) -> None:
    if os.environ.get("CI") == "true":
        pytest.fail("CI must build the firmware: " + why)
    pytest.skip(why)


def build_dir(board: str) -> Path:
    return cache_root() / "firmware-tests" / board


_built: dict[str, object] = {}


def built(board: str = "pico", qemu: bool = False):
    """texelpad.firmware.build.Built for boards/<board> (qemu: an STM32 board's emulated
    twin), built once per session."""
    key = board + ("-qemu" if qemu else "")
    if key not in _built:
        why = why_not_build("stm32" if board == "pyboard" else "rp2")
        if why:
            skip_or_fail(why)
        from texelpad.firmware.build import build_firmware
        root = Path(__file__).resolve().parents[2]
        _built[key] = build_firmware(root / "boards" / board, build_dir(board), qemu=qemu)
    return _built[key]
