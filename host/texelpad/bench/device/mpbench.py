# Device side of `texelpad bench`: runs under the MicroPython unix port and
# the instrument interpreters (MicroPython + ulab in float32 and float64,
# CircuitPython + ulab with 30-bit floats and no viper) with the `texel`
# package on its path (MICROPYPATH). Device code: no type hints, no
# f-strings, only modules every one of them has (CircuitPython has no
# `traceback`; CircuitPython boards have no ticks_us: ticks come from
# texel.compat, which has them everywhere).
#
#   micropython mpbench.py JOB.json
#
# JOB.json: {"timing": params, "cases": [[name, params], ...], "repeat": N,
#            "outdir": path, "variants": [names] or null, "calibrate": rounds,
#            "formats": params of the plan-by-format timing (default: timing),
#            "churn": measure heap churn with gc off (default true)}
# (texelpad bench --chip rp2040 runs main() on the emulated Pico with no cases:
# timings only, its flash is no place for 38 KB maps)
# Output: one JSON document per line on stdout, in this order:
#   {"event": "info", ...}                       runtime, variants, calibration
#   {"event": "plan", "v": 1|2, "plan_us": [...]}  the timing case's plan in
#                                                each texture format
#   {"event": "timing", "variant": v, ...}       per variant, as it finishes
#   {"event": "case", "variant": v, "case": c}   per map written to outdir
#   {"event": "error", "variant": v, ...}        a variant (or one of its
#                                                cases) raised; the rest go on
#   {"event": "done"}
# Maps are written as raw uint16 (native byte order) to
# outdir/<variant>__<case>.u16 and compared with the float64 reference on the
# host. Variants: "int" (viper fill where the port has it), "int-py" (the same
# engine with its pure-Python fill; only where "int" is viper), "pure", "ulab"
# (if the build has ulab).
import gc
import json
import math
import sys

import texel
from texel import compat
from texel.compat import ticks_diff, ticks_us
from texel.gen import engine_int, engine_pure, engine_ulab

_FILL_NATIVE = engine_int._fill


def emit(doc):
    print(json.dumps(doc))


def variants_here():
    names = ["int"]
    if engine_int.VIPER:
        names.append("int-py")
    names.append("pure")
    if engine_ulab.available():
        names.append("ulab")
    return names


def select(variant):
    """The engine module for a variant; sets the int engine's fill."""
    engine_int._fill = _FILL_NATIVE
    if variant == "int":
        return engine_int
    if variant == "int-py":
        engine_int._fill = engine_int._fill_py
        return engine_int
    if variant == "pure":
        return engine_pure
    if variant == "ulab":
        return engine_ulab
    raise ValueError("unknown variant %r" % (variant,))


def _us(t0, t1):
    return ticks_diff(t1, t0)


def time_variant(variant, params, repeat, churn=True):
    m = select(variant)
    plan = texel.make_plan(params)
    out = m.render_u16(plan)            # warm-up: builds the sine table
    plan_us = []
    synth_us = []
    for _ in range(repeat):
        gc.collect()
        t0 = ticks_us()
        plan = texel.make_plan(params)
        t1 = ticks_us()
        gc.collect()
        t2 = ticks_us()
        m.render_u16(plan, out)
        t3 = ticks_us()
        plan_us.append(_us(t0, t1))
        synth_us.append(_us(t2, t3))
    # Memory: bytes still held by one rendered map (after a collection), and
    # bytes allocated while rendering it with the collector off (heap churn,
    # an upper bound on the transient peak).
    # (churn=False on a board: with the collector off, the boxed floats of
    # the pure and ulab engines fill a Pico's heap - a MemoryError, not a figure)
    out = None
    gc.collect()
    base = gc.mem_alloc()
    if churn:
        gc.disable()
    try:
        r = m.render_u16(plan)
        churn = gc.mem_alloc() - base if churn else None
    finally:
        gc.enable()
    gc.collect()
    held = gc.mem_alloc() - base
    map_bytes = len(r) * 2
    r = None
    gc.collect()
    base = gc.mem_alloc()
    p2 = texel.make_plan(params)
    gc.collect()
    plan_bytes = gc.mem_alloc() - base
    del p2
    engine_int._fill = _FILL_NATIVE
    return {"event": "timing", "variant": variant, "plan_us": plan_us, "synth_us": synth_us,
            "map_bytes": map_bytes, "held_bytes": held, "churn_bytes": churn,
            "plan_bytes": plan_bytes, "samples": plan.n, "texels": plan.count}


def render_case(variant, name, params, outdir):
    m = select(variant)
    plan = texel.make_plan(params)
    r = m.render_u16(plan)
    path = outdir + "/" + variant + "__" + name + ".u16"
    with open(path, "wb") as f:
        f.write(r)
    engine_int._fill = _FILL_NATIVE
    r = None
    gc.collect()
    return {"event": "case", "variant": variant, "case": name, "path": path,
            "samples": plan.n, "fraction_above_nyquist": plan.fraction_above_nyquist()}


# --- calibration: the unix port's own per-op costs -------------------------
# Used on the host to check the op-count model of the RP2040 estimate against
# times measured here (same counting rules, unix-port costs).
def _loop_empty(n):
    i = 0
    while i < n:
        i += 1
    return i


def _loop_int(n):
    i = 0
    x = 12345
    d = 2718281
    while i < n:
        x = (x + d) & 0x0FFFFFFF
        x = (x + d) & 0x0FFFFFFF
        i += 1
    return x


def _loop_float(n):
    i = 0
    x = 1.0
    c = 1.0000001
    while i < n:
        x = x * c
        x = x * c
        i += 1
    return x


def _ident(a):
    return a


def _loop_call(n):
    i = 0
    x = 1
    f = _ident
    while i < n:
        x = f(x)
        i += 1
    return x


def _loop_builtin(n):
    i = 0
    x = 1.0
    f = math.sin
    while i < n:
        x = f(x)
        i += 1
    return x


def _time_us(fn, n):
    gc.collect()
    t0 = ticks_us()
    fn(n)
    return _us(t0, ticks_us())


def calibrate(repeat):
    """Per-op costs of this interpreter (us). The loops are timed in turns and
    the fastest of `repeat` rounds kept for each, so a busy host skews all of
    them alike rather than one."""
    n = 20000
    loops = [("empty", _loop_empty), ("int", _loop_int), ("float", _loop_float),
             ("call", _loop_call), ("builtin", _loop_builtin)]
    viper = None
    if engine_int.VIPER:
        from texel.gen import sine_table
        tab = sine_table.table()
        buf = compat.u16_buffer(19200)

        def viper(k):
            return _FILL_NATIVE(buf, 0, 19200, 0, 123457, tab, 16384)
        loops.append(("viper", viper))
    best = {}
    for _ in range(repeat):
        for name, fn in loops:
            dt = _time_us(fn, n)
            if name not in best or dt < best[name]:
                best[name] = dt
    empty = best["empty"]
    # the loop counter costs 2 ops (compare, add) per iteration; _loop_int has
    # 4 integer ops per iteration, _loop_float 2 float ops
    cal = {"int_op_us": (best["int"] - empty) / (4.0 * n),
           "float_op_us": (best["float"] - empty) / (2.0 * n),
           "call_us": (best["call"] - empty) / float(n),
           "builtin_call_us": (best["builtin"] - empty) / float(n),
           "loop_iteration_us": empty / float(n)}
    if viper is not None:
        cal["viper_iteration_us"] = best["viper"] / 19200.0
    return cal


def _describe(e):
    """An exception as text: its traceback where the port can print one
    (sys.print_exception), else its type and message."""
    msg = "%s: %s" % (type(e).__name__, e)
    pe = getattr(sys, "print_exception", None)
    if pe is not None:
        try:
            import io
            buf = io.StringIO()
            pe(e, buf)
            return buf.getvalue().strip() or msg
        except Exception:
            pass
    return msg


def _error(variant, e, case=None):
    engine_int._fill = _FILL_NATIVE
    gc.collect()
    doc = {"event": "error", "variant": variant, "error": _describe(e)}
    if case is not None:
        doc["case"] = case
    return doc


def time_formats(params, repeat):
    """The plan alone, in texture format 1 (the float plan) and 2 (the
    integer plan, gen/plan_int.py), for the same parameters."""
    out = []
    for v in (1, 2):
        p = dict(params)
        p["v"] = v
        texel.make_plan(p)              # warm-up: imports, tables
        us = []
        for _ in range(repeat):
            gc.collect()
            t0 = ticks_us()
            texel.make_plan(p)
            us.append(_us(t0, ticks_us()))
        out.append({"event": "plan", "v": v, "plan_us": us})
    return out


def main(job_path):
    with open(job_path) as f:
        job = json.load(f)
    repeat = job.get("repeat", 5)
    names = job.get("variants") or variants_here()
    here = variants_here()
    names = [v for v in names if v in here]
    impl = sys.implementation
    emit({"event": "info", "impl": compat.IMPL, "version": list(impl.version),
          "machine": getattr(impl, "_machine", None), "build": getattr(impl, "_build", None),
          "platform": sys.platform, "float_bits": compat.FLOAT_BITS, "viper": engine_int.VIPER,
          "ulab": compat.ulab_version(), "variants": names, "heap_free": compat.heap_free(),
          "calibration": calibrate(job.get("calibrate", 25))})
    try:
        for doc in time_formats(job.get("formats") or job["timing"], repeat):
            emit(doc)
    except Exception as e:
        emit(_error("plan formats", e))
    for v in names:
        try:
            doc = time_variant(v, job["timing"], repeat, job.get("churn", True))
        except Exception as e:          # MemoryError included: report it, go on
            emit(_error(v, e))
            continue
        emit(doc)
        for name, params in job["cases"]:
            try:
                doc = render_case(v, name, params, job["outdir"])
            except Exception as e:
                doc = _error(v, e, name)
            emit(doc)
    emit({"event": "done"})


if __name__ == "__main__":
    main(sys.argv[1])
