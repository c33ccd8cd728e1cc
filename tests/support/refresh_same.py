"""A script for a board (an emulated chip) that runs the C core's refresh
(refresh_core.c, as that chip's build compiled it) and refresh_viper.core on
the same word array W, refresh by refresh, and compares every state word and
the CC word: a FastRefresh of a board file's sensor on stand-in registers
(arrays), a scene built there, the finger sweeping, jumping, dropping out and
lifted. Its last line: repr((same, refreshes, first difference, the table's
kinds, _texelcore.BUILD)), after `prefix`. tests/firmware/test_firmware_pico.py
(the Cortex-M0+ firmware) and tests/host/test_emulated_stm32.py (the armv7emsp
native module) run it."""
from __future__ import annotations

from typing import Any

_RUN = r"""
def _rs_run():
    import _texelcore as c
    from texel.runtime import boards, refresh_viper as RV, scene as S
    from texel.runtime.refresh_fast import FastRefresh
    from texel.runtime.sensor import make_sensor
    from texel.runtime.duty import DutyLaw
    from texel import compat
    board = boards.load(%(board)r)
    disp = board["display"]
    sc = S.build(S.validate(%(scene)r, disp), disp)
    sensor = make_sensor(board["sensor"], [lambda: 0], disp["positions"], 8333)
    r = FastRefresh(sensor, DutyLaw(3675, 0.5), lambda d: None, lambda: 0,
                    compat.ticks_us, compat.ticks_diff, 120, 77)
    r.swap(sc)
    st = r._S
    kinds = sorted(set(sc._t[4 * i + 2] for i in range(sc.count)))
    x = 12345
    same = 0
    first = None
    n = 0
    for k in range(%(n)d):
        x = (x * 48271) %% 0x7FFFFFFF
        m = k %% 300
        raw = (2000 + (k * 211) %% 61000) if m < 200 else (x %% 65536 if m < 230 else
               (x %% 300 if m < 240 else 1000 + (k * 37) %% 63000))
        r._clk[0] = (k * 120 + 5) & 0x3FFFFFFF
        r._adc[1] = raw
        before = list(st)
        cc0 = r._cc[0]
        RV.core(RV._WA)
        a = list(st) + [r._cc[0]]
        for i in range(len(before)):
            st[i] = before[i]
        r._cc[0] = cc0
        c.refresh(RV._W)
        b = list(st) + [r._cc[0]]
        n += 1
        if a == b:
            same += 1
        elif first is None:
            first = (k, raw, [i for i in range(len(a)) if a[i] != b[i]])
    return (same, n, first, kinds, c.BUILD)
"""


def script(board: str, scene: dict[str, Any], n: int, stop_app: bool = False,
           prefix: str = "") -> str:
    """The script for board file `board`, `n` refreshes over `scene`. stop_app:
    stop texel.app around it (its interrupt would run the same W) and start the
    board again after; prefix: what the result line starts with."""
    body = _RUN % {"board": board, "scene": scene, "n": n}
    if stop_app:
        body += ("import texel.app as _rs_A\n_rs_A.stop()\ntry:\n    _rs_out = _rs_run()\n"
                 "finally:\n    _rs_A.start(%r)\n" % board)
    else:
        body += "_rs_out = _rs_run()\n"
    return body + "print(%r + repr(_rs_out))\n" % prefix
