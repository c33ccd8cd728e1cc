"""The C core's texel_check (device/cmod/texelcore/texelcore_api.h) against
the Python checks it stands in for (runtime/kinds/texel.py check): textures
that test both, and the script that runs both on a MicroPython with the core
(the unix port with the x64 native module, the firmware on the emulated
Pico: its float32) and prints what it found.

Every texture either gets the same canonical dict from both - the same keys,
values and types - or the fast path returns None and the Python path decides.
The cases: the hard ones by hand (range edges, grid ties within GRID_TIE,
format 2's Nyquist point, ints in float keys, bools, big ints, None, NaN,
words) and random ones that mix them."""
from __future__ import annotations

import random

_EDGES = [0, 1, -1, 2, 0.0, 1.0, -0.5, 19.747, 19.7475, 19.748, -20.0, -20.0005, 5.0, -30.0,
          20.0, 0.001, 0.0005, 0.0009999, 94.339, 94.3396, 94.34, 0.01, 0.0099, True, False,
          None, "x", "reset", "continuous", "nan", "inf", 1 << 29, 1 << 30, 1 << 31,
          (1 << 32) - 1, 1 << 32, 1 << 70, 50, 1048576, 1048577, 3.0, 2.5, 1.5, 12.3455,
          12.3445, 12.3450000001, 12.34549, 12.34551, -12.9, 0.0125, 0.0115, [1.0], {}]
_KEYS = ["pitch_db", "irregularity_db", "texel_samples", "quant_db", "seed", "gain", "v",
         "band_limit_cpmm", "min_cpmm", "phase", "length_samples", "bogus", 7]
_FLOATS = ("band_limit_cpmm", "min_cpmm", "quant_db", "gain", "pitch_db", "irregularity_db")


def _value(r: random.Random, k) -> object:
    if r.random() < 0.6:
        return r.choice(_EDGES)
    if k in _FLOATS:
        return round(r.uniform(0.01, 94.339), r.choice((2, 3, 4, 6)))
    return r.choice((1, 2, 7, 50, 4096, r.randrange(1 << 32)))


def cases(n: int, seed: int = 5) -> list[dict]:
    """n textures (dicts as a scene's region holds them; "nan"/"inf" stand
    for the floats, which a literal cannot carry: the script makes them)."""
    r = random.Random(seed)
    out = [{"kind": "texel", "pitch_db": 6.0, "irregularity_db": -12.9, "seed": 7, "v": 2},
           {"kind": "texel", "pitch_db": 6.0, "irregularity_db": -12.9, "v": 1},
           {"kind": "texel", "pitch_db": 19.747, "irregularity_db": 5.0, "texel_samples": 1,
            "quant_db": 0.001, "seed": 4294967295, "gain": 0, "band_limit_cpmm": 94.339,
            "min_cpmm": 94.338, "phase": "reset"},
           {"kind": "texel", "pitch_db": -20, "irregularity_db": -30, "min_cpmm": None,
            "band_limit_cpmm": None, "phase": "continuous"},
           {"kind": "texel", "pitch_db": 1.0, "irregularity_db": -3.0, "min_cpmm": 5.0,
            "band_limit_cpmm": 5.0}]
    while len(out) < n:
        t = {"kind": "texel",
             "pitch_db": round(r.uniform(-20, 19.747), r.choice((0, 1, 2, 3, 4, 6))),
             "irregularity_db": round(r.uniform(-30, 5), r.choice((1, 3, 5)))}
        for k in r.sample(_KEYS, r.randrange(0, 5)):
            t[k] = _value(r, k)
        if len(out) % 3 == 0:
            t["v"] = r.choice((1, 2, 2))
        if len(out) % 11 == 0:
            t.pop("pitch_db")
        out.append(t)
    return out


# Runs on MicroPython with texel importable; %(cases)s is cases()' list as a
# literal, or an expression that reads one (script(path=)). One function, run
# and deleted: a board keeps none of its names (a stock Pico's heap is tight).
SCRIPT = r"""
def _tc_run():
    import json
    from texel.runtime.kinds import texel as KT
    from texel import compat
    _F = {"nan": float("nan"), "inf": float("inf")}
    def real(t):
        return dict((k, _F.get(v, v) if isinstance(v, str) else v) for k, v in t.items())
    def slow(tex):
        f = KT._fast
        KT._fast = False
        try:
            return ("ok", KT.check("t", tex, 5000))
        except ValueError as e:
            return ("err", str(e))
        finally:
            KT._fast = f
    c = compat.core()
    info = {"build": c and c.BUILD, "n": 0, "fast": 0, "fallback_ok": 0, "plans": 0, "c_plans": 0,
            "c_option_plans": 0, "bad": []}
    for t in %(cases)s:
        tex = real(t)
        f = KT.fast_check(tex)
        s = slow(tex)
        info["n"] += 1
        if f is None:
            info["fallback_ok"] += s[0] == "ok"
            continue
        info["fast"] += 1
        if s[0] != "ok" or s[1] != f or sorted(f) != sorted(s[1]) or \
                [repr(f[k]) for k in sorted(f)] != [repr(s[1][k]) for k in sorted(f)] or \
                [type(f[k]).__name__ for k in sorted(f)] != [type(s[1][k]).__name__ for k in sorted(f)]:
            info["bad"].append([repr(t), repr(f), repr(s)])
            continue
        # and plan_of: the C core's plan in one call against PlanInt's
        n = 700 if f["texel_samples"] < 3 else 5000
        a = KT.plan_of(f, n)
        if KT._plan_c and KT._plan_c(f, n, KT._table()) is not None:
            info["c_plans"] += 1        # (format 2: the C plan ran)
            if f.get("min_cpmm") is not None or f.get("phase", "continuous") != "continuous":
                info["c_option_plans"] += 1     # (with seed 001's options: tc_plan_options)
        p, KT._plan_c = KT._plan_c, False
        try:
            b = KT.plan_of(f, n)
        finally:
            KT._plan_c = p
        info["plans"] += 1
        if [bytes(a[0]), bytes(a[1]), a[2], a[3]] != [bytes(b[0]), bytes(b[1]), b[2], b[3]]:
            info["bad"].append([repr(t), "plan_of", repr(a[2:]), repr(b[2:])])
    print(json.dumps(info))
_tc_run()
del _tc_run
"""


def script(cases_: list[dict] | None = None, path: str | None = None) -> str:
    """SCRIPT over cases_ inline, or over the literal in the file at path
    (a long list: a command line has a length limit)."""
    if path is not None:
        return SCRIPT % {"cases": "eval(open(%r).read())" % path}
    return SCRIPT % {"cases": repr(cases_)}


def scenes(n: int, seed: int = 7) -> list[dict]:
    """n scenes for scene.py's region fast path (region_check): touching and
    overlapping regions, boundaries as floats, ints, bools, out of range, at
    the display's end and past it by less than half a position, regions that
    round to no position, extra and missing keys, every kind's textures."""
    r = random.Random(seed)
    texs = [{"kind": "texel", "pitch_db": 4.0, "irregularity_db": -12.9, "seed": 7, "v": 2},
            {"kind": "constant", "level": 0.5}, {"kind": "reference", "name": "4sin"},
            {"kind": "texel", "pitch_db": "x", "irregularity_db": 0.0}, {"kind": "bogus"}, 5]
    edges = [0, 0.0, 1, 50.88, 101.76, 101.7626, 101.7627, 101.77, 102, -0.0, -1, True,
             None, "1", "nan", 0.0026, 0.0027, 0.00265, 50.8826, 1 << 40, 7.5]
    out = []
    while len(out) < n:
        if len(out) % 2:                # a partition of the display: mostly valid
            k = r.randrange(1, 17)
            cuts = sorted(round(r.uniform(0, 101.76), r.choice((1, 2, 3, 4))) for _ in range(k - 1))
            cuts = [r.choice((0, 0.0))] + cuts + [r.choice((101.76, 101.7626, 101.77))]
            out.append({"regions": [{"start_mm": cuts[j], "end_mm": cuts[j + 1],
                                     "texture": dict(texs[r.choice((0,) * 12 + (1, 2, 3))])}
                                    for j in range(k)]})
            continue
        regs = []
        for _ in range(r.randrange(1, 5)):
            a = r.choice(edges) if r.random() < 0.4 else round(r.uniform(0, 101.76), 3)
            b = r.choice(edges) if r.random() < 0.4 else round(r.uniform(0, 101.76), 3)
            if isinstance(a, float) and isinstance(b, float) and a > b and r.random() < 0.8:
                a, b = b, a
            t = r.choice(texs)
            reg = {"start_mm": a, "end_mm": b, "texture": dict(t) if isinstance(t, dict) else t}
            if r.random() < 0.05:
                reg["extra"] = 1
            if r.random() < 0.05:
                del reg[r.choice(["start_mm", "end_mm", "texture"])]
            regs.append(reg)
        out.append({"regions": regs})
    return out


# scene.py's _check with the C core's fast paths and without: the same
# canonical scene and spans, or the same refusal
SCENE_SCRIPT = r"""
def _tc_run():
    import json
    from texel.runtime import scene as S
    from texel.runtime.kinds import texel as KT
    from texel import compat
    _F = {"nan": float("nan")}
    def real(sc):
        for reg in sc["regions"]:
            for k in ("start_mm", "end_mm"):
                if reg.get(k) == "nan":
                    reg[k] = _F["nan"]
        return sc
    def run(sc, fast):
        f, g = S._fast, KT._fast
        if not fast:
            S._fast = KT._fast = False
        try:
            c, spans, pos, dx = S._check(sc, {"positions": 19200, "dx_um": 5.3})
            return ("ok", repr(sorted((k, v) for k, v in c.items() if k != "regions")),
                    repr([(sorted(x), x["start_mm"], x["end_mm"], sorted(x["texture"].items()))
                          for x in c["regions"]]), repr(spans),
                    repr([(type(x["start_mm"]).__name__, type(x["end_mm"]).__name__)
                          for x in c["regions"]]))
        except ValueError as e:
            return ("err", str(e))
        finally:
            S._fast, KT._fast = f, g
    info = {"fast_region": bool(S._fast_region()), "n": 0, "ok": 0, "fast_regions": 0, "bad": []}
    lim = S._lim(19200 * 5.3 / 1000.0, 5.3)                  # scene._check's
    for sc in %(scenes)s:
        sc = real(sc)
        a = run(sc, True)
        b = run(sc, False)
        info["n"] += 1
        info["ok"] += a[0] == "ok"
        if info["fast_region"]:
            for reg in sc["regions"]:
                if S._fast(reg, lim, 19200, 5.3) is not None:
                    info["fast_regions"] += 1
        if a != b:
            info["bad"].append([repr(sc), a, b])
    print(json.dumps(info))
_tc_run()
del _tc_run
"""


def scene_script(scenes_: list[dict] | None = None, path: str | None = None) -> str:
    if path is not None:
        return SCENE_SCRIPT % {"scenes": "eval(open(%r).read())" % path}
    return SCENE_SCRIPT % {"scenes": repr(scenes_)}


def run_batches(exec_, script_fn, items: list, size: int) -> dict:
    """script_fn over items in batches of `size` through exec_ (a link's
    exec: one compile per batch, small enough for a playing board's heap);
    the batches' reports summed (counts added, "bad" lists joined)."""
    import json
    total: dict = {}
    for i in range(0, len(items), size):
        out = exec_(script_fn(items[i:i + size]))
        info = json.loads(out.strip().splitlines()[-1])
        for k, v in info.items():
            if isinstance(v, bool) or not isinstance(v, (int, list)):
                total[k] = v
            else:
                total[k] = total.get(k, [] if isinstance(v, list) else 0) + v
    return total
