# Region kind "texel": the Single-Pitch Texel generator's texture over the
# region (seed 000; docs/generator.md). The texture is the texel parameters
# (gen/params.py KEYS) but length_samples, which the region sets to its own
# length, and the texture options (params.OPTION_KEYS: in the canonical
# texture only when set); checked by gen/params.py validate, so its messages
# are the generator's own.
#
# Played from its plan (how K_PLAN: t28, d28 - 8 bytes per texel - evaluated
# at the finger's position by Scene.amp) when no engine is asked for and its
# texels are 5 .. PLAN_MAX_L samples long and shorter than the region (where
# the plan is smaller than the map; k*d stays a small int in 16 x 14-bit limb
# products); else rendered by the engine asked for into a region-long buffer,
# or by default by the integer engine (a scene is the same texture on every
# runtime) into 1 KB chunks (kinds.new_chunks: no block of the region's length
# on a board's heap for 1-4-sample texels, or one texel longer than the region).
from array import array
from ...compat import u16_one_block
from ...gen.params import validate as texel_validate
from ...gen.params import SPEC as TEXEL_SPEC
from ...gen.params import KEYS as _TEXEL_ALL_KEYS
from ...gen.params import OPTION_KEYS as TEXEL_OPTIONS
from ...gen.check import BIG, expected, fail, got, plain_str, check_keys
from . import K_BUF, K_PLAN, K_CHUNK, CHUNK_BITS, new_chunks

NAME = "texel"
TEXEL_KEYS = tuple(k for k in _TEXEL_ALL_KEYS if k != "length_samples")
KEYS = ("kind",) + TEXEL_KEYS
OPTIONS = TEXEL_OPTIONS
_TEXEL_ANY = TEXEL_KEYS + TEXEL_OPTIONS     # the options: only when set
SHARED = False              # rendered by an engine: the same texture may be asked of another
PLAN_MAX_L = 65535


# The C core's fast path (texelcore_api.h texel_check): the canonical texture of
# a texture it accepts as it comes, else None and the checks below decide and
# word the refusal. 0.2 of a Pico's 2.6 ms a region (bench/firmware.py);
# tests/gen/test_texel_core.py and tests/support/texel_check.py hold the two
# to the same dicts.
_fast = None                # the core's texel_check, False where there is none
_spec = None                # its spec: Python's own bounds and defaults (_c_spec)
C_KEYS = ("pitch_db", "irregularity_db", "texel_samples", "quant_db", "seed", "gain", "v",
          "band_limit_cpmm", "min_cpmm")        # texelcore_api.h tc_ck_names' order


def _c_spec():
    from ...gen import params as P
    from ...gen.grid import GRID_TIE
    out = [GRID_TIE, P.QUANT_DB_MIN]
    for k in C_KEYS:
        kind, default, lo, hi = P.SPEC[k] if k in P.SPEC else P.OPTION_SPEC[k]
        out += [lo, hi, default]
    return tuple(out)


def fast_check(tex):
    """The C core's canonical texture of tex (a dict), or None: none there,
    or one it leaves to check() (every refusal)."""
    global _fast, _spec
    if _fast is None:
        from ...compat import core
        c = core()
        _fast = (c and getattr(c, "texel_check", None)) or False
        if _fast:
            _spec = _c_spec()
    if _fast:
        return _fast(tex, _spec)    # (None for a non-dict)
    return None


_regions = None             # the core's regions_check, False where there is none


def fast_regions(regs, lim, positions, dx_um):
    """The C core's regions_check (texelcore_api.h) of a scene's regions,
    texel_check for its texel textures - one entry a region: (region dict,
    start, end), region_check's 5-tuple, or None; or, every region checked
    whole and none overlapping, scene._check's (regions, spans) - or None
    where there is no such core (or fast_check is off)."""
    global _regions
    if _fast is None:
        fast_check(None)            # (sets _fast and _spec)
    if not _fast:
        return None
    if _regions is None:
        from ...compat import core
        _regions = getattr(core(), "regions_check", None) or False
    return _regions(regs, lim, positions, dx_um, _spec) if _regions else None


def check(path, tex, n):
    c = fast_check(tex)
    if c is not None:
        return c
    if "length_samples" in tex:
        fail(path + ".length_samples", "set by the region (here %d samples); remove it" % n)
    # (the unknown-key message lists KEYS and the options: tests/runtime/
    # test_scene.py pins it as TEXEL_ALLOWED)
    check_keys(path, tex, KEYS, TEXEL_OPTIONS)
    p = {}
    for k in TEXEL_KEYS:
        if k in tex:
            v = tex[k]
            # texel.validate shows the value with %r: hand it only values
            # whose repr is small and the same on every port; describe the
            # rest here, in its format.
            if not (v is None or isinstance(v, (bool, float))
                    or (isinstance(v, int) and -BIG < v < BIG)
                    or (isinstance(v, str) and plain_str(v))):
                kind, _, lo, hi = TEXEL_SPEC[k]
                expected(path + "." + k, "an int" if kind == "i" else "a number", lo, hi,
                         got(v))
            p[k] = v
    for k in TEXEL_OPTIONS:     # texel.validate bounds what it shows of these
        if k in tex:
            p[k] = tex[k]
    p["length_samples"] = n
    try:
        c = texel_validate(p)
        err = None
    except ValueError as e:
        err = str(e)
    if err is not None:
        # "pitch_db: nan is not finite ..." -> "<path>.pitch_db: ..."
        cut = err.find(":")
        if cut > 0 and (err[:cut] in TEXEL_SPEC or err[:cut] in TEXEL_OPTIONS):
            raise ValueError(path + "." + err)
        fail(path, err)
    out = {"kind": "texel"}
    for k in _TEXEL_ANY:
        if k in c:
            out[k] = c[k]
    return out


_plan_int = None            # gen.plan_int.PlanInt, imported at the first format-2 region
_gain_q14 = None            # gen.engine_int.gain_q14, imported at the first plan
_plan_c = None              # the C core's plan, False where there is none
_table = None               # gen.plan_int_tables.table, for it


def plan_of(tex, n):
    """(t28, d28, L, gain_q14) of a texel region n samples long: what
    engine_int needs to make any one sample (the float parts of the plan are
    dropped). Format 2 (gen/plan_int.py) from the region's already validated
    keys, without its log pitches and without a second validation; its class
    is looked up once (an import statement runs the import machinery on every
    call: with the parameter copy, 2 of a Pico's 11.5 ms here)."""
    global _plan_int, _gain_q14, _plan_c, _table
    if _plan_c is None:
        from ...compat import core
        c = core()
        _plan_c = (c and getattr(c, "plan", None)) or False
        if _plan_c:
            from ...gen.plan_int_tables import table
            _table = table
    if _plan_c:
        # the C core's plan in one call (texelcore_api.h plan: format 2, with
        # seed 001's options too, else None): 0.65 of a Pico's 2.2 ms here;
        # with the options, no import of gen/options.py (10.8 ms) and PlanInt
        r = _plan_c(tex, n, _table())
        if r is not None:
            both, count, L, g = r
            mv = memoryview(both)
            return (mv[:count], mv[count:], L, g)
    if _gain_q14 is None:
        from ...gen.engine_int import gain_q14
        _gain_q14 = gain_q14
    p = dict(tex)
    del p["kind"]
    p["length_samples"] = n
    if p["v"] == 2:
        if _plan_int is None:
            from ...gen.plan_int import PlanInt
            _plan_int = PlanInt
        pl = _plan_int(p, keep_y=False)
    else:
        from ... import make_plan
        pl = make_plan(p)
    return (pl.t28, pl.d28, pl.L, _gain_q14(pl.gain))


def fill(tex, n, buf, engine, dx_um):
    from ... import render_u16
    p = {}
    for k in _TEXEL_ANY:
        if k in tex:
            p[k] = tex[k]
    p["length_samples"] = n
    # A scene plays what a board plays: the integer engine unless the caller
    # asks for another (so a scene is the same texture on every runtime).
    if engine is None:                      # the board's way: into chunks (store)
        from ... import make_plan
        from ...gen.engine_int import render_chunks
        render_chunks(make_plan(p), buf, CHUNK_BITS)
        return
    if engine == "numpy":
        # engine_numpy.render_u16 cannot write an ndarray into an array('H')
        # slice (CPython only; memory is no concern there): render, then copy.
        q = render_u16(p, engine="numpy")
        buf[:] = array("H", q.tobytes())
    else:
        render_u16(p, engine=engine, out=buf)


def on_plan(tex, n, engine):
    """Whether a region plays from its plan (how K_PLAN)."""
    if engine is not None:
        return False
    L = tex["texel_samples"]
    return 4 < L <= PLAN_MAX_L and L < n


def need(tex, n, engine):
    if on_plan(tex, n, engine):
        return 8 * ((n + tex["texel_samples"] - 1) // tex["texel_samples"])
    return 2 * n


def block(tex, n, engine):
    if on_plan(tex, n, engine):
        return 0
    return 2 * n if engine is not None else 2 * min(n, 1 << CHUNK_BITS)


def store(tex, n, engine):
    if engine is None:
        L = tex["texel_samples"]
        if 4 < L <= PLAN_MAX_L and L < n:      # on_plan, inline (a call: ~20 us on a Pico)
            return K_PLAN, plan_of(tex, n), None
        ch = new_chunks(n)
        return K_CHUNK, ch, ch
    buf = u16_one_block(n)                  # exactly region-long
    return K_BUF, buf, buf


def describe(tex):
    return {"pitch_db": tex["pitch_db"], "irregularity_db": tex["irregularity_db"],
            "seed": tex["seed"], "v": tex["v"]}


def words(d):
    return "texel pitch %s dB, irregularity %s dB, seed %s, format %s" % (
        d["pitch_db"], d["irregularity_db"], d["seed"], d.get("v", 1))


def label(d):
    return "texel %.1f/%.1f dB, seed %d" % (d["pitch_db"], d["irregularity_db"], d["seed"])
