# Device side of `texelpad bench-refresh`: runs under the MicroPython unix
# port with the `texel` package and mpbench.py (for its per-op calibration)
# on its path (MICROPYPATH). Device code: no type hints, no f-strings, only
# modules the unix port has.
#
#   micropython -X heapsize=64M mp_refresh_bench.py JOB.json
#
# JOB.json: {"seconds": S, "push_repeat": N, "calibrate_repeat": N}, or
#           {"phase": "churn"} (run with a large heap: builds with gc off)
# Output: one JSON document per line on stdout:
#   {"event": "info", ...}                  runtime, swipe, calibration
#   {"event": "memory", "scene": k, ...}    per scene: Scene.nbytes, gc.mem_alloc delta
#   {"event": "churn", "scene": k, ...}     (churn phase) bytes allocated by a build
#   {"event": "refresh", "variant": v, ...} per refresh implementation: batch times
#   {"event": "component", "variant": v, "name": c, ...}   per component
#   {"event": "push", "variant": v, "scene": k, ...}       per scene: push() split
#   {"event": "skip", "variant": v, "reason": ...}         a variant that cannot run
#   {"event": "done"}
#
# Timing: time.ticks_us around batches of BATCH calls, never around one call
# (a 1 us clock and the ticks calls themselves would swamp a ~3 us refresh).
# Every timed batch is paired with an empty batch - the same loop without
# the call - timed right after it; the host subtracts the empty loop's median
# and divides by BATCH. Batch and empty loop alternate, so a busy host slows
# both alike.
import gc
import json
import sys
import time

import texel
import texel.app as app
import texel.wire as wire
from texel import compat
from texel.runtime import scene

import mpbench

BATCH = 100                     # calls per timed batch
MAX_BATCHES = 4096              # per component measurement (preallocated: a 2 MB heap)
MAX_REFRESH_BATCHES = 16384     # per refresh measurement
RECORD = 1024                   # duties the virtual board records (cleared every batch)
PERIOD_US = 120                 # virtual time between refreshes (8,333 Hz)
# The scripted swipe (texel.wire.finger keyframes, ms and mm), repeated for as long
# as the bench runs: touch at 5 mm, swipe to 95 mm at 100 mm/s across both
# halves of the split screen, hold 50 ms, lift 40 ms, and back.
SWIPE_MS = [(0, 5.0), (900, 95.0), (950, 95.0), (960, None), (1000, 95.0),
            (1900, 5.0), (1950, 5.0), (1960, None), (2000, None)]
CYCLE_US = 2000000

WIDTH_MM = 101.76               # 19,200 positions of 5.3 um
TEXEL = {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7}


def _regions16():
    regs = []
    pitch = WIDTH_MM / 16
    for k in range(16):
        if k % 2:
            tex = {"kind": "reference", "name": "4sin"}
        else:
            tex = {"kind": "texel", "pitch_db": 6.3, "irregularity_db": -12.9, "seed": k}
        a = round(k * pitch, 4)
        regs.append({"start_mm": a, "end_mm": round(a + 4.0, 4), "texture": tex})
    return {"regions": regs}


SCENES = [
    ("split", "the study's split screen: reference 4sin 0-50.88 mm | texel (6.3 dB, "
              "-12.9 dB, seed 7) 50.88-101.76 mm", app.DEFAULT_SCENE),
    ("texel", "one full-screen texel region (6.3 dB, -12.9 dB, seed 7)",
     {"regions": [{"start_mm": 0, "end_mm": WIDTH_MM, "texture": TEXEL}]}),
    ("reference", "one full-screen reference region (4sin)",
     {"regions": [{"start_mm": 0, "end_mm": WIDTH_MM,
                   "texture": {"kind": "reference", "name": "4sin"}}]}),
    ("regions16", "16 small regions, 4 mm each every 6.36 mm, texel and reference 4sin "
                  "alternating", _regions16()),
    ("constant", "constant only: one full-screen region at level 0.5",
     {"regions": [{"start_mm": 0, "end_mm": WIDTH_MM,
                   "texture": {"kind": "constant", "level": 0.5}}]}),
]


def emit(doc):
    print(json.dumps(doc))


def _us(t0, t1):
    return time.ticks_diff(t1, t0)


def _times(n=MAX_BATCHES):
    from array import array
    gc.collect()
    return array("i", bytes(4 * n)), array("i", bytes(4 * n))


def _list(a, k):
    return [a[i] for i in range(k)]


class _Clock:
    # stands in for the virtual board in the empty loops: the same attribute
    # store as hw.now = t, without moving the finger
    def __init__(self):
        self.now = 0


# --- the timed loops (each paired with its empty twin) -----------------------
def loop_refresh(cb, hw, t, n):
    i = 0
    while i < n:
        hw.now = t
        cb(None)
        t += PERIOD_US
        i += 1
    return t


def loop_refresh_empty(cb, hw, t, n):
    i = 0
    while i < n:
        hw.now = t
        t += PERIOD_US
        i += 1
    return t


def loop_timed(f, hw, a, j, n):
    # f() at the virtual times a[j], a[j+1], ...: a sensor read
    end = j + n
    while j < end:
        hw.now = a[j]
        f()
        j += 1


def loop_timed_empty(f, hw, a, j, n):
    end = j + n
    while j < end:
        hw.now = a[j]
        j += 1


def loop_call1(f, a, j, n):
    end = j + n
    while j < end:
        f(a[j])
        j += 1


def loop_call1_empty(f, a, j, n):
    end = j + n
    while j < end:
        a[j]
        j += 1


def loop_call2(f, a, j, n):
    # f(x, 0): the viper core's (raw, t)
    end = j + n
    while j < end:
        f(a[j], 0)
        j += 1


# --- starting the display -----------------------------------------------------
def start(fast):
    """app.start on the virtual board; fast=False: the Python refresh even
    where viper would be the default. An app without the `fast` option
    (before the fused refresh) gets a plain start."""
    try:
        return app.start("virtual", fast=fast, record=RECORD)
    except TypeError as e:
        if "fast" not in str(e) and "keyword" not in str(e):
            raise
        if fast:
            return None
        return app.start("virtual", record=RECORD)


def _loop_ticks(n):
    i = 0
    f = time.ticks_us
    while i < n:
        f()
        i += 1
    return i


def calibrate_extra(repeat):
    """The refresh's one op class bench_model's calibration lacks: a built-in
    call with small-int arguments and result (ticks_us, ticks_diff,
    read_u16), timed like mpbench.calibrate (fastest of `repeat`, minus the
    empty loop)."""
    n = 20000
    best = {}
    for _ in range(repeat):
        for name, fn in (("empty", mpbench._loop_empty), ("ticks", _loop_ticks)):
            dt = mpbench._time_us(fn, n)
            if name not in best or dt < best[name]:
                best[name] = dt
    return {"int_builtin_call_us": (best["ticks"] - best["empty"]) / float(n)}


def viper_variant():
    """(how, reason): how the fused viper refresh is switched on here -
    "fast" (app.start(..., fast=True)), "install" (refresh_viper.install(rt)),
    or None with the reason it is skipped."""
    if not compat.HAS_VIPER:
        return None, "this MicroPython build has no viper emitter"
    try:
        import texel.runtime.refresh_viper as rv
    except ImportError as e:
        return None, "no module texel.runtime.refresh_viper (%s)" % (e,)
    except Exception as e:
        return None, "texel.runtime.refresh_viper does not import: %s: %s" % (type(e).__name__, e)
    if hasattr(rv, "install"):
        return "install", None
    if hasattr(rv, "FastRefresh"):
        return "fast", None
    return None, "texel.runtime.refresh_viper has neither install(rt) nor FastRefresh"


def start_viper(how):
    if how == "fast":
        st = start(True)
        if st is None:
            raise RuntimeError("app.start has no `fast` option")
        return st
    import texel.runtime.refresh_viper as rv
    start(False)
    rv.install(app._rt)
    return app.status()


def _mode(default):
    st = app.status()
    return st.get("refresh", default)


# --- the measurements ---------------------------------------------------------
def lifted_fraction():
    """Share of one swipe cycle's refreshes with the finger lifted."""
    from texel.hw.virtual import Finger
    f = Finger([(int(t * 1000), None if p is None else int(p / 0.0053 + 0.5))
                for (t, p) in SWIPE_MS])
    n = CYCLE_US // PERIOD_US
    lifted = 0
    for k in range(n):
        if f.at(k * PERIOD_US) < 0:
            lifted += 1
    return lifted / n


def measure_refresh(seconds):
    """Per-batch wall time of BATCH refreshes as the board's timer would call
    them (hw.cb: the callback app.start gave the board), during the swipe."""
    rt = app._rt
    hw = rt.hw
    cb = hw.cb
    r = rt.refresh
    clock = _Clock()
    wire.finger(SWIPE_MS)
    cycle0 = hw.now
    t = hw.now
    # warm-up: a few batches not timed
    for _ in range(5):
        hw.clear_record()
        t = loop_refresh(cb, hw, t, BATCH)
    r.worst_us = 0
    count0 = r.count
    v0 = t
    batch_us, empty_us = _times(MAX_REFRESH_BATCHES)
    k = 0
    gc.collect()
    budget = int(seconds * 1000000)
    w0 = time.ticks_us()
    while (_us(w0, time.ticks_us()) < budget or k < 5) and k < MAX_REFRESH_BATCHES:
        if t - cycle0 >= CYCLE_US:
            hw.now = t
            wire.finger(SWIPE_MS)
            cycle0 = t
        hw.clear_record()
        t0 = time.ticks_us()
        t = loop_refresh(cb, hw, t, BATCH)
        t1 = time.ticks_us()
        loop_refresh_empty(cb, clock, t, BATCH)
        t2 = time.ticks_us()
        batch_us[k] = _us(t0, t1)
        empty_us[k] = _us(t1, t2)
        k += 1
    hw.now = t
    return {"batch": BATCH, "batch_us": _list(batch_us, k), "empty_us": _list(empty_us, k),
            "refreshes": (r.count - count0) & 0x3FFFFFFF,
            "virtual_s": (t - v0) / 1e6,
            "per_call_worst_us": r.worst_us, "overruns": r.overruns, "faults": r.faults}


def swipe_inputs(rt):
    """Inputs for the component loops over one swipe cycle from hw.now: the
    virtual times and raw ADC readings of every refresh, and for the m
    refreshes with the finger down its true position, the split screen's
    amplitude there and its duty (preallocated arrays: a 2 MB heap).
    Returns (n, ts, raws, m, positions, amps, duties); n and m are multiples
    of BATCH."""
    from array import array
    hw = rt.hw
    wire.finger(SWIPE_MS)
    t0 = hw.now
    n = (CYCLE_US // PERIOD_US) // BATCH * BATCH
    gc.collect()
    ts = array("i", bytes(4 * n))
    raws = array("i", bytes(4 * n))
    positions = array("i", bytes(4 * n))
    amps = array("i", bytes(4 * n))
    duties = array("i", bytes(4 * n))
    sc = rt.refresh.scene
    law = rt.law
    m = 0
    for k in range(n):
        t = t0 + k * PERIOD_US
        ts[k] = t
        hw.now = t
        raws[k] = hw.adc_read(0)
        p = hw.finger.at(t)
        if p >= 0:
            positions[m] = p
            a = sc.amp(p)
            amps[m] = a
            duties[m] = law.duty(a)
            m += 1
    hw.now = t0
    return n, ts, raws, m // BATCH * BATCH, positions, amps, duties


def time_component(seconds, f, fe, args, n_inputs, before=None):
    """Batch and empty-batch times of fe/f(*args, j, BATCH) over the inputs."""
    batch_us, empty_us = _times()
    k = 0
    j = 0
    # warm-up
    if before:
        before()
    f(*(args + (0, BATCH)))
    gc.collect()
    budget = int(seconds * 1000000)
    w0 = time.ticks_us()
    while (_us(w0, time.ticks_us()) < budget or k < 5) and k < MAX_BATCHES:
        if before:
            before()
        t0 = time.ticks_us()
        f(*(args + (j, BATCH)))
        t1 = time.ticks_us()
        fe(*(args + (j, BATCH)))
        t2 = time.ticks_us()
        batch_us[k] = _us(t0, t1)
        empty_us[k] = _us(t1, t2)
        k += 1
        j += BATCH
        if j >= n_inputs:
            j = 0
    return {"batch": BATCH, "batch_us": _list(batch_us, k), "empty_us": _list(empty_us, k)}


def _wrap_f(loop, f):
    # bind the callable under test as the loop's first argument
    def run(*a):
        return loop(f, *a)
    return run


class _StubParts:
    # sensor, scene and duty law that return constants: Refresh.step with
    # these measures the step's own bookkeeping
    idle = 0

    def read(self):
        return 100

    def amp(self, pos):
        return 1000

    def duty(self, amp):
        return 50


def _stub_set_duty(counts):
    pass


def _step_with_stub_parts():
    """A Refresh whose parts do nothing, timed by the real clock (as on rp2:
    cost_ticks = time.ticks_us, a built-in)."""
    from texel.runtime.refresh import Refresh
    stub = _StubParts()
    r = Refresh(stub, stub, _stub_set_duty, time.ticks_us, time.ticks_diff, PERIOD_US, 0)
    r.swap(stub)
    return r.step


def measure_components(variant, seconds):
    rt = app._rt
    hw = rt.hw
    n, ts, raws, m, positions, amps, duties = swipe_inputs(rt)
    out = []
    if variant == "python":
        sensor = rt.sensor
        clear = hw.clear_record
        comps = [
            ("sensor.read", "%s.read(): virtual ADC + calibration, filter, velocity, "
                            "compensation" % type(sensor).__name__,
             loop_timed, loop_timed_empty, sensor.read, (hw, ts), n, None),
        ]
        rd = getattr(sensor, "_read", None)
        if rd is not None:
            comps.append(("virtual_adc", "the virtual ADC alone (finger script + calibration; "
                                         "included in sensor.read; a board reads its ADC "
                                         "instead)",
                          loop_timed, loop_timed_empty, rd, (hw, ts), n, None))
        sc = rt.refresh.scene
        comps += [
            ("scene.amp", "Scene.amp(pos) of the split screen (%d regions) at the swipe's "
                          "positions" % sc.count,
             loop_call1, loop_call1_empty, sc.amp, (positions,), m, None),
            ("law.duty", "DutyLaw.duty(amp) of those amplitudes",
             loop_call1, loop_call1_empty, rt.law.duty, (amps,), m, None),
            ("hw.set_duty", "VirtualHw.set_duty(counts): records (time, duty) into arrays",
             loop_call1, loop_call1_empty, rt.refresh.set_duty, (duties,), m, clear),
        ]
        comps.append(("step_body", "Refresh.step with stub parts (sensor, scene, law, "
                                   "set_duty returning constants) and time.ticks_us as its "
                                   "cost clock: the step's own bookkeeping, as on rp2",
                      loop_refresh, loop_refresh_empty, _step_with_stub_parts(),
                      (_Clock(),), 1 << 30, None))
    else:
        import texel.runtime.refresh_viper as rv
        f = getattr(rv, "refresh", None)
        regs = getattr(rt.refresh, "_adc", None)
        if f is None or regs is None:
            return out

        def loop_regs(f, a, j, n):
            # the generic path's ADC word holds the raw reading
            end = j + n
            while j < end:
                regs[1] = a[j]
                f(None)
                j += 1

        def loop_regs_empty(f, a, j, n):
            end = j + n
            while j < end:
                regs[1] = a[j]
                j += 1
        comps = [("viper_core", "refresh_viper.refresh(None): sensor + scene + duty fused in "
                                "one viper function, input from its ADC word (split screen)",
                  loop_regs, loop_regs_empty, f, (raws,), n, None)]
    for name, what, loop, empty, f, args, n, before in comps:
        r = time_component(seconds, _wrap_f(loop, f), _wrap_f(empty, f), args, n, before)
        r.update({"event": "component", "variant": variant, "name": name, "what": what})
        out.append(r)
    hw.clear_record()
    return out


def measure_memory():
    """What each scene holds once built: Scene.nbytes (its own account) and
    the gc.mem_alloc() growth after a collection (every object it keeps:
    buffers, region table, the canonical source dict, the Scene)."""
    disp = {"positions": 19200, "dx_um": 5.3}
    for key, what, src in SCENES:
        canonical = scene.validate(src, disp)
        gc.collect()
        a0 = gc.mem_alloc()
        sc = scene.build(canonical, disp)
        gc.collect()
        held = gc.mem_alloc() - a0
        emit({"event": "memory", "scene": key, "what": what, "regions": sc.count,
              "nbytes": sc.nbytes, "buffer_bytes": sc.buffer_bytes,
              "table_bytes": sc.table_bytes, "mem_alloc_delta": held})
        del sc
        canonical = None
        gc.collect()


def measure_churn():
    """Bytes allocated while building each scene with the collector off (heap
    churn: garbage a board's collector must reclaim during a push; bounds
    the build's transient peak). Needs a large heap: its own run."""
    disp = {"positions": 19200, "dx_um": 5.3}
    for key, what, src in SCENES:
        canonical = scene.validate(src, disp)
        gc.collect()
        gc.disable()
        try:
            a0 = gc.mem_alloc()
            sc = scene.build(canonical, disp)
            churn = gc.mem_alloc() - a0
        finally:
            gc.enable()
        del sc
        canonical = None
        gc.collect()
        emit({"event": "churn", "scene": key, "build_churn_bytes": churn})


def measure_pushes(variant, repeat):
    """app.push() of each scene: total wall time, validate alone, and the
    build/swap split app records in status()["last_push"]. On the virtual
    board app's clock is the stepped one (a push takes 0 us of virtual
    time), so rt.ticks/rt.diff are pointed at the real clock meanwhile."""
    rt = app._rt
    disp = rt.board["display"]
    saved = (rt.ticks, rt.diff)
    rt.ticks = time.ticks_us
    rt.diff = time.ticks_diff
    try:
        for key, what, src in SCENES:
            rows = []
            for _ in range(repeat):
                gc.collect()
                t0 = time.ticks_us()
                scene.validate(src, disp)
                t1 = time.ticks_us()
                gc.collect()
                t2 = time.ticks_us()
                st = app.push(src)
                t3 = time.ticks_us()
                lp = st["last_push"]
                rows.append([_us(t0, t1), _us(t2, t3), lp["build_us"], lp["swap_us"],
                             lp["scene_bytes"]])
                st = None
            emit({"event": "push", "variant": variant, "scene": key, "mode": _mode(variant),
                  "runs": rows, "fields": ["validate_us", "push_us", "build_us", "swap_us",
                                           "scene_bytes"]})
        app.push(app.DEFAULT_SCENE)
    finally:
        rt.ticks, rt.diff = saved


def run_variant(variant, how, seconds, push_repeat):
    if variant == "python":
        start(False)
    else:
        start_viper(how)
    try:
        rt = app._rt
        st = app.status()
        mode = st.get("refresh", "python")
        if variant == "python" and mode != "python":
            raise RuntimeError("asked for the Python refresh, app runs %r" % (mode,))
        if variant == "viper" and (mode == "python" or type(rt.refresh).__name__ == "Refresh"):
            raise RuntimeError("asked for the viper refresh, app runs the Python one")
        r = measure_refresh(seconds)
        r.update({"event": "refresh", "variant": variant, "mode": mode,
                  "callback": "%s.step" % type(rt.refresh).__name__,
                  "period_us": rt.period_us, "hz": rt.hz, "pwm_top": rt.hw.top})
        emit(r)
        for c in measure_components(variant, seconds / 4.0):
            emit(c)
        measure_pushes(variant, push_repeat)
    finally:
        app.stop()


def main(job_path):
    with open(job_path) as f:
        job = json.load(f)
    if job.get("phase") == "churn":
        emit({"event": "info", "phase": "churn", "heap_free": compat.heap_free()})
        measure_churn()
        emit({"event": "done"})
        return
    seconds = float(job.get("seconds", 2.0))
    push_repeat = int(job.get("push_repeat", 3))
    how, why = viper_variant()
    emit({"event": "info", "impl": compat.IMPL, "version": list(sys.implementation.version),
          "platform": sys.platform, "texel": texel.__version__, "viper": compat.HAS_VIPER,
          "viper_refresh": how, "viper_refresh_reason": why, "heap_free": compat.heap_free(),
          "batch": BATCH, "period_us": PERIOD_US, "swipe_ms_mm": SWIPE_MS,
          "lifted_fraction": lifted_fraction(),
          "calibration": mpbench.calibrate(int(job.get("calibrate_repeat", 9))),
          "calibration_extra": calibrate_extra(int(job.get("calibrate_repeat", 9)))})
    measure_memory()
    run_variant("python", None, seconds, push_repeat)
    if how is None:
        emit({"event": "skip", "variant": "viper", "reason": why})
    else:
        try:
            run_variant("viper", how, seconds, push_repeat)
        except Exception as e:
            emit({"event": "skip", "variant": "viper",
                  "reason": "the viper refresh failed: %s: %s" % (type(e).__name__, e)})
    emit({"event": "done"})


if __name__ == "__main__":
    main(sys.argv[1])
