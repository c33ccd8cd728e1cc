"""Benchmarks: scripts that print figures (and JSON); they never fail on time.

    engines   speed against error of every render engine on every runtime
    refresh   the cost of one refresh, scene memory, push/swap latency
    link      deploy time, push latency, bytes on the wire, a push soak
    opcount   the op-count model (a cross-check, labelled an estimate)
    chip      the emulated RP2040's own clock: plan, push and refresh on the chip
    lab       texelpad lab: slider change -> new scene playing on the virtual board
    study_compare  guided exploration against preference search, answers to 1 dB
    device/   the scripts that run under MicroPython (package data, not modules)
"""

import math


def jsonable(x):
    """x with numpy arrays and scalars as lists and Python numbers, non-finite
    floats as None (strict JSON), and the keys that start with "_" left out
    (a report's working data: maps, fits)."""
    import numpy as np
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items() if not str(k).startswith("_")}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (np.floating, float)):
        return None if not math.isfinite(float(x)) else float(x)
    if isinstance(x, (np.integer, np.bool_)):
        return x.item()
    return x
