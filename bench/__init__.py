"""The research benchmarks: scripts that print figures (and JSON); they never
fail on time. Not part of the installed package (texelpad's own benchmarks,
`texelpad bench | bench-refresh | bench-link`, are texelpad.bench). Each runs
from the repository root as `.venv/bin/python -m bench.<name>`; bench/README.md
lists them with their latest results (bench/results/).

    study_compare     guided exploration against preference search, answers to 1 dB
    encode            the texel encoder: speed, against people, against itself
    felt_calibration  the felt model's calibration and the encoders on the nine
    brush_fit         the Tactile Paintbrush's analysis: fits per wavenumber, comparison
    brush_paint       painting a brush: cost per runtime, bytes, the round trip
    brush_painting    what painting makes: does a painted map read like its source
    lab               texelpad lab: slider change -> new scene playing on the virtual board
    firmware          issue 19's goals on the emulated Pico running the texelpad firmware
"""

import math
from contextlib import contextmanager


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


@contextmanager
def deployed_pico(say, res):
    """A stock emulated Pico (../shared/instruments/rp2emu) with texelpad
    deployed, booted and stopped around the block: yields its port. Raises
    SystemExit when this machine cannot run it; on the way out puts the
    emulator's summary in res["emulator_summary"] and the block's wall time
    (boot and deploy included) in res["wall_s"]."""
    import time
    from texelpad.deploy.install import deploy
    from texelpad.link.board import connect
    from texelpad.sim.emulated import EmulatedPico, why_not
    why = why_not()
    if why:
        raise SystemExit("the emulated Pico cannot run here: %s" % why)
    t_wall = time.monotonic()
    emu = EmulatedPico()
    try:
        say("booting the emulated RP2040")
        emu.start()
        with connect(emu.port, check=False, import_image=False, timeout=60) as b:
            deploy(b, progress=lambda m: say("deploy: " + m))
        yield emu.port
    finally:
        res["emulator_summary"] = emu.stop().strip()
        res["wall_s"] = round(time.monotonic() - t_wall, 1)
