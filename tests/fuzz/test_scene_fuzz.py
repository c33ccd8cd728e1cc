"""Fuzz target "scenes": arbitrary JSON-like values and near-valid scenes
through the host's check (texelpad.link.board.host_check: the literal rule,
then the board's own validation) and the device's
texel.runtime.scene.validate / build, on a small display (2,000 positions of
5.3 um: builds stay fast).

Inputs: (a) JSON-like junk (any nesting of None, bools, ints of any size,
floats with NaN/inf/-0.0/subnormals, strings short and 100,000 long, lists,
dicts whose keys mix the scene's own words with any text); (b) valid scenes
(1..16 regions of every kind, samples uploads of 1 .. 19,200 values, names,
notes, idle levels) with 1..4 mutations at random places: wrong types,
huge/tiny/non-finite numbers, int <-> float <-> str <-> bool, extra and
missing keys, wrapped and deeply nested values (to 3,000 levels), long
strings, overlapping / swapped / empty / shifted regions, other kinds,
uploads of 0, odd and too many values, both "values" and "u16"; some leaves
as numpy scalars and arrays (host_check only: the device never sees numpy).

Properties, per case:
- host_check and validate return or raise ValueError, nothing else; a
  refusal's message is one line of at most 500 characters whose head (the
  text before the first ": ") is a path: scene, value, regions[3].texture.u16[17] ...
- neither changes its input (deep, NaN-aware, list vs tuple);
- for plain input they agree: host_check accepts only what validate accepts,
  and refuses what validate accepts only for its size limit on the link;
- an accepted scene's canonical form re-validates to itself (type for type)
  and builds, and Scene.amp() gives a uint16 at every position.
"""
from __future__ import annotations

import contextlib
import copy
import math
import re
import sys

import numpy as np
import pytest
from hypothesis import given, strategies as st

import fuzzlib
import texel
from texel.gen import params as P
from texel.runtime import scene as S
from texel.runtime.kinds import samples as KS
from texelpad.link.board import host_check

FUZZ_TARGET = "scenes"
pytestmark = pytest.mark.fuzz
D = {"positions": 2000, "dx_um": 5.3}
DX_MM = D["dx_um"] / 1000.0
TOTAL_MM = D["positions"] * DX_MM              # 10.6
NAMES = texel.reference_names()
NAN, INF = float("nan"), float("inf")

# --- values ---------------------------------------------------------------------------

WORDS = ["regions", "idle_amplitude", "name", "notes", "start_mm", "end_mm", "texture", "kind",
         "texel", "reference", "constant", "samples", "values", "u16", "fit", "tile", "stretch",
         "level", "pitch_db", "irregularity_db", "texel_samples", "length_samples", "quant_db",
         "seed", "gain", "v", "band_limit_cpmm", "4sin", "pink", " kind", "Kind", "regions\n",
         "", "__class__", "é€😀", "a: b", "x" * 300, "\x00", "'\"\\"]
SPECIAL_FLOATS = [NAN, -NAN, INF, -INF, 0.0, -0.0, 5e-324, -5e-324, 2.2250738585072014e-308,
                  1.7976931348623157e308, -1.7976931348623157e308, 1e-300, 1e300, 0.5,
                  0.9999999999999999, 1.0000000000000002, 65535.5, 19.747, 19.747000000000003,
                  -20.000000000000004, TOTAL_MM, math.nextafter(TOTAL_MM, INF),
                  TOTAL_MM + DX_MM / 2, 0.0026, 0.00265, 0.00264]
SPECIAL_INTS = [0, 1, -1, 2, 65535, 65536, -65536, 19200, 19201, 2 ** 31, 2 ** 32 - 1, 2 ** 32,
                2 ** 62, 2 ** 63 - 1, 2 ** 63, 2 ** 64 - 1, 2 ** 64, -(2 ** 63), -(2 ** 63) - 1,
                10 ** 30, 10 ** 400, -(10 ** 400), P.TEXEL_MAX, P.TEXEL_MAX + 1, P.SEED_MAX,
                P.SEED_MAX + 1]
LONG_TEXT = st.sampled_from(["x" * 65, "y" * 2001, "z" * 100_000, "é" * 70, "\n" * 10,
                             "\ud800", "line1\r\nline2", "\x1b[2J", "'" * 200])

_text = st.one_of(st.sampled_from(WORDS), st.text(max_size=20), LONG_TEXT)
_int = st.one_of(st.sampled_from(SPECIAL_INTS), st.integers(), st.integers(-5, 70000))
_float = st.one_of(st.sampled_from(SPECIAL_FLOATS), st.floats(), st.floats(0, 12))
_scalar = st.one_of(st.none(), st.booleans(), _int, _float, _text)
_key = st.one_of(st.sampled_from(WORDS), st.text(max_size=8))
json_like = st.recursive(
    _scalar, lambda ch: st.one_of(st.lists(ch, max_size=6), st.dictionaries(_key, ch, max_size=6)),
    max_leaves=25)


def nested(depth: int, leaf=0, kind: str = "list"):
    v = leaf
    for _ in range(depth):
        v = [v] if kind == "list" else {"a": v}
    return v


# --- valid scenes on D ------------------------------------------------------------------------

def _idx(draw, n: int) -> int:
    """About uniform in range(n) (hypothesis favours the low end of small ranges)."""
    return draw(st.integers(0, 2 ** 24)) % n


def _finite(lo, hi):
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


@st.composite
def texture(draw, n_positions: int):
    kind = S.KINDS[_idx(draw, 4)]
    if kind == "texel":
        t = {"kind": "texel", "pitch_db": draw(_finite(P.PITCH_DB_MIN, P.PITCH_DB_MAX)),
             "irregularity_db": draw(_finite(P.IRREG_DB_MIN, P.IRREG_DB_MAX))}
        extras = {"texel_samples": st.one_of(st.integers(1, 300), st.integers(1, P.TEXEL_MAX)),
                  "quant_db": st.one_of(st.just(0.0), _finite(P.QUANT_DB_MIN, P.QUANT_DB_MAX)),
                  "seed": st.integers(0, P.SEED_MAX), "gain": _finite(0, 1), "v": st.just(1),
                  "band_limit_cpmm": st.one_of(st.none(), _finite(0.01, P.NYQUIST_CPMM))}
        for k in draw(st.lists(st.sampled_from(sorted(extras)), unique=True)):
            t[k] = draw(extras[k])
        return t
    if kind == "reference":
        return {"kind": "reference", "name": draw(st.sampled_from(NAMES))}
    if kind == "constant":
        return {"kind": "constant", "level": draw(st.one_of(_finite(0, 1), st.sampled_from([0, 1])))}
    key = ("values", "u16")[_idx(draw, 2)]
    if _idx(draw, 8):
        m = draw(st.integers(1, 40))
    else:                       # odd and large sizes (a full screen now and then)
        m = draw(st.sampled_from([1, 2, 3, n_positions - 1, n_positions, n_positions + 1,
                                  1999, 2000, 2001, 4097, KS.MAX_SAMPLES]))
    m = max(1, min(m, KS.MAX_SAMPLES))
    a, b = draw(st.integers(0, 65535)), draw(st.integers(0, 65535))
    if key == "u16":
        vals = [(a * i + b) % 65536 for i in range(m)]
    else:
        vals = [((a * i + b) % 65536) / 65535.0 for i in range(m)]
    t = {"kind": "samples", key: tuple(vals) if _idx(draw, 5) == 0 else vals}
    fit = (None, "tile", "stretch")[_idx(draw, 3)]
    if fit:
        t["fit"] = fit
    return t


@st.composite
def valid_scene(draw):
    n = draw(st.one_of(st.integers(1, 3), st.integers(1, S.MAX_REGIONS)))
    cuts = sorted(draw(st.lists(st.integers(0, D["positions"]), min_size=2 * n, max_size=2 * n,
                                unique=True)))
    spans = [[cuts[2 * i], cuts[2 * i + 1]] for i in range(n)]
    for i in range(1, n):
        if _idx(draw, 2):
            spans[i][0] = spans[i - 1][1]                     # touching
    order = draw(st.permutations(range(n)))
    regions = []
    for i in order:
        s, e = spans[i]
        style = _idx(draw, 3)
        mm = (lambda p: round(p * DX_MM, 4)) if style == 0 else \
             (lambda p: p * DX_MM) if style == 1 else (lambda p: (p + 0.3) * DX_MM if p < D["positions"] else p * DX_MM)
        r = {"start_mm": mm(s), "end_mm": mm(e), "texture": draw(texture(e - s))}
        regions.append(r)
    scene = {"regions": regions}
    if _idx(draw, 3) == 0:
        scene["idle_amplitude"] = draw(st.integers(0, 65535))
    if _idx(draw, 4) == 0:
        scene["name"] = draw(st.text(min_size=1, max_size=S.NAME_MAX))
    if _idx(draw, 4) == 0:
        scene["notes"] = draw(st.one_of(st.text(max_size=50), st.just("n" * S.NOTES_MAX)))
    return scene


# --- mutations -------------------------------------------------------------------------------

def _slots(v, path=(), out=None):
    """Every (path) to a value inside v (long lists: a few elements; not
    below 20 levels)."""
    if out is None:
        out = []
    if len(path) >= 20:
        return out
    if isinstance(v, dict):
        for k in list(v):
            out.append(path + (k,))
            _slots(v[k], path + (k,), out)
    elif isinstance(v, (list, tuple)):
        idx = range(len(v)) if len(v) <= 8 else [0, 1, len(v) // 2, len(v) - 1]
        for i in idx:
            out.append(path + (i,))
            _slots(v[i], path + (i,), out)
    return out


def _get(root, path):
    for k in path:
        root = root[k]
    return root


def _set(root, path, value):
    """root with the value at path replaced (tuples are rebuilt)."""
    if not path:
        return value
    parent = _get(root, path[:-1])
    k = path[-1]
    if isinstance(parent, tuple):
        lst = list(parent)
        lst[k] = value
        return _set(root, path[:-1], tuple(lst))
    parent[k] = value
    return root


def _containers(root, kind):
    return [p for p in [()] + _slots(root) if isinstance(_get(root, p), kind)]


def _numeric_twist(draw, v):
    choices = [NAN, INF, -INF, -0.0, 5e-324, 1e308, 2 ** 64, -(2 ** 63) - 1, 10 ** 400, True,
               False, None, "1.5", [v], (v,), {"v": v}]
    if not isinstance(v, (list, tuple, dict)) and not (isinstance(v, int) and abs(v) > 10 ** 4000):
        choices.append(str(v))
    if isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v) < 1e300:
        choices += [-v, v * 1000, v + 1e-9, v - 1e-9, float(v), v + 1, v - 1]
        if isinstance(v, float) and math.isfinite(v):
            choices += [int(v), math.nextafter(v, INF), math.nextafter(v, -INF), v / 3]
    return choices[_idx(draw, len(choices))]


def _regions(root):
    if isinstance(root, dict) and isinstance(root.get("regions"), (list, tuple)):
        regs = root["regions"]
        if isinstance(regs, tuple):
            root["regions"] = regs = list(regs)
        return regs
    return None


def _textures(root):
    regs = _regions(root) or []
    return [r["texture"] for r in regs if isinstance(r, dict) and isinstance(r.get("texture"), dict)]


@st.composite
def mutate(draw, root):
    """Apply one mutation to root (returns the new root: a replaced root is
    possible) and a word saying which."""
    op = _idx(draw, 14)
    slots = _slots(root)
    if op == 0 and slots:                                      # any value -> junk
        p = slots[_idx(draw, len(slots))]
        return _set(root, p, draw(json_like)), "junk"
    if op == 1 and slots:                                      # twist a value
        p = slots[_idx(draw, len(slots))]
        return _set(root, p, _numeric_twist(draw, _get(root, p))), "twist"
    if op == 2:                                                # delete a key
        dicts = [p for p in _containers(root, dict) if _get(root, p)]
        if dicts:
            d = _get(root, dicts[_idx(draw, len(dicts))])
            del d[list(d)[_idx(draw, len(d))]]
            return root, "delete"
    if op == 3:                                                # add a key
        dicts = _containers(root, dict)
        if dicts:
            d = _get(root, dicts[_idx(draw, len(dicts))])
            key = draw(st.one_of(st.sampled_from(WORDS), _key, st.integers(-2, 2), st.none(),
                                 st.tuples(st.integers(0, 2))))
            d[key] = draw(st.one_of(json_like, st.sampled_from([0, 1, 0.5, "tile", [1, 2]])))
            return root, "add key"
    if op == 4 and slots:                                      # deep nesting
        p = slots[_idx(draw, len(slots))]
        depth = draw(st.sampled_from([2, 5, 15, 16, 17, 50, 200, 1000, 3000]))
        return _set(root, p, nested(depth, _get(root, p), ("list", "dict")[_idx(draw, 2)])), "nest"
    if op == 5 and slots:                                      # a long or odd string
        p = slots[_idx(draw, len(slots))]
        return _set(root, p, draw(LONG_TEXT)), "string"
    regs = _regions(root)
    if op == 6 and regs:                                       # overlap: duplicate a region
        k = _idx(draw, len(regs))
        with deep():                                            # (a region nested 3,000 deep)
            regs.insert(_idx(draw, len(regs) + 1), copy.deepcopy(regs[k]))
        return root, "duplicate region"
    if op == 7 and regs:                                       # move a region's ends
        r = regs[_idx(draw, len(regs))]
        if isinstance(r, dict) and "start_mm" in r and "end_mm" in r:
            how = _idx(draw, 5)
            s, e = r["start_mm"], r["end_mm"]
            if how == 0:
                r["start_mm"], r["end_mm"] = e, s
            elif how == 1:
                r["end_mm"] = s
            elif how == 2 and isinstance(s, (int, float)):
                r["end_mm"] = s + draw(st.sampled_from([1e-9, 0.001, DX_MM / 2, DX_MM / 2 + 1e-9]))
            elif how == 3 and isinstance(s, (int, float)) and isinstance(e, (int, float)):
                d = draw(st.sampled_from([DX_MM / 2, -DX_MM / 2, DX_MM, 1.0, -1.0, TOTAL_MM]))
                r["start_mm"], r["end_mm"] = s + d, e + d
            else:
                r["end_mm"] = draw(st.sampled_from([TOTAL_MM, TOTAL_MM + 0.0026, TOTAL_MM + 0.0027,
                                                    TOTAL_MM * 2, -0.001, 0]))
            return root, "move region"
    if op == 8 and regs is not None:                           # region count
        how = _idx(draw, 3)
        if how == 0:
            root["regions"] = []
        elif how == 1 and regs:
            root["regions"] = regs * (S.MAX_REGIONS // max(1, len(regs)) + 1)
        else:
            root["regions"] = [{"start_mm": i * 0.6, "end_mm": i * 0.6 + 0.5,
                                "texture": {"kind": "constant", "level": 0.5}}
                               for i in range(draw(st.integers(15, 18)))]
        return root, "region count"
    texs = _textures(root)
    if op == 9 and texs:                                       # another kind
        t = texs[_idx(draw, len(texs))]
        t["kind"] = draw(st.one_of(st.sampled_from(list(S.KINDS) + ["Texel", "noise", ""]), _scalar))
        return root, "kind"
    samples = [t for t in texs if t.get("kind") == "samples"]
    if op == 10 and samples:                                   # upload sizes and keys
        t = samples[_idx(draw, len(samples))]
        key = "u16" if "u16" in t else "values"
        seq = t.get(key)
        if isinstance(seq, (list, tuple)) and seq:
            how = _idx(draw, 4)
            if how == 0:
                m = draw(st.sampled_from([0, 1, 2, 3, 7, 1999, 2001, KS.MAX_SAMPLES,
                                          KS.MAX_SAMPLES + 1, 30000]))
                t[key] = [seq[i % len(seq)] for i in range(m)]
            elif how == 1:
                t["u16" if key == "values" else "values"] = list(seq)      # the other key too
                if _idx(draw, 2):
                    del t[key]                                             # or instead
            elif how == 2:
                lst = list(seq)
                lst[_idx(draw, len(lst))] = draw(st.one_of(_scalar, st.sampled_from(
                    [65535.0, 65536, -1, 1.0000001, True, NAN])))
                t[key] = lst
            else:
                t["fit"] = draw(st.one_of(st.sampled_from(["tile", "stretch", "Tile", "zoom"]), _scalar))
            return root, "upload"
    if op == 11 and isinstance(root, dict):                    # the scene's own words
        k = ("name", "notes", "idle_amplitude")[_idx(draw, 3)]
        root[k] = draw(st.one_of(_scalar, st.sampled_from(["", "n", "n" * 64, "n" * 65,
                                                           "n" * 2000, "n" * 2001, 65535, 65536])))
        return root, "scene words"
    if op == 12 and slots:                                     # numpy leaves (host_check only)
        p = slots[_idx(draw, len(slots))]
        v = _get(root, p)
        conv = _numpy_of(draw, v)
        if conv is not None:
            return _set(root, p, conv), "numpy"
    if op == 13:                                               # the whole scene wrapped
        return draw(st.sampled_from([[root], (root,), {"scene": root}, {"regions": root}])), "wrap"
    return root, "none"


def _numpy_of(draw, v):
    kinds = [np.float64, np.float32, np.float16, np.int64, np.int8, np.uint64, np.bool_,
             np.longdouble, np.complex64, np.str_]
    try:
        if isinstance(v, (list, tuple)) and v and len(v) < 20000:
            dt = [np.float64, np.float32, np.uint16, np.int64, np.bool_, object, np.complex128,
                  np.int8][_idx(draw, 8)]
            with np.errstate(all="ignore"):
                return np.array(v, dtype=dt)
        if isinstance(v, (int, float, str, bool)) and not (isinstance(v, int) and abs(v) > 2 ** 63):
            with np.errstate(all="ignore"):
                return kinds[_idx(draw, len(kinds))](v)
    except (ValueError, TypeError, OverflowError):
        return None
    if isinstance(v, str) and v:
        return np.datetime64("2026-01-01")
    return None


@st.composite
def inputs(draw):
    """(scene, how it was made)."""
    if _idx(draw, 5) == 0:
        return draw(json_like), ["junk"]
    scene = draw(valid_scene())
    ops = []
    for _ in range(draw(st.sampled_from([0, 1, 1, 1, 2, 2, 3, 4]))):
        scene, op = draw(mutate(scene))
        ops.append(op)
    return scene, ops


# --- checks ---------------------------------------------------------------------------------

@contextlib.contextmanager
def deep():
    """The test's own walks (deepcopy, same) over values nested 3,000 deep:
    a higher recursion limit for them only - never around the code under test."""
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, 30000))
    try:
        yield
    finally:
        sys.setrecursionlimit(old)


def same(a, b) -> bool:
    """Deep equality that tells NaN == NaN, -0.0 != 0.0, list != tuple, types apart."""
    if type(a) is not type(b):
        return False
    if isinstance(a, float):
        return (a != a and b != b) or (a == b and math.copysign(1, a) == math.copysign(1, b))
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict):
        return list(a) == list(b) and all(same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")
    if isinstance(a, np.generic):
        return bool(a == b) or (a != a and b != b)
    return a == b


# a path: a name, then [indexes] and .keys ("regions[3].texture.u16[17]", "scene", "value"
# for a whole value the literal rule refuses, "start_mm" for a key of a junk dict; the
# literal rule shows other keys as they are: "value.þ[0]")
HEAD = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*(\[|\.|$)")


class BadMessage(AssertionError):
    """A refusal whose message breaks the rules; .cause is the ValueError."""

    def __init__(self, text: str, cause: ValueError):
        super().__init__(text)
        self.cause = cause


def check_message(e: ValueError, where: str) -> None:
    msg = str(e)
    if "\n" in msg or "\r" in msg:
        raise BadMessage("%s: a message of several lines: %r" % (where, msg[:300]), e)
    if not msg.isprintable():
        raise BadMessage("%s: control characters in the message: %r" % (where, msg[:300]), e)
    if not 0 < len(msg) <= 500:
        raise BadMessage("%s: a message of %d characters: %r" % (where, len(msg), msg[:300]), e)
    if not (HEAD.match(msg.split(": ", 1)[0]) or msg.startswith("value is ")):   # the whole value
        raise BadMessage("%s: the message does not start with a path: %r" % (where, msg[:300]), e)


def _is_plain(v, depth=0) -> bool:
    if isinstance(v, (np.generic, np.ndarray)):
        return False
    if isinstance(v, dict):
        return all(_is_plain(k, depth) and _is_plain(x, depth + 1) for k, x in v.items())
    if isinstance(v, (list, tuple)):
        return all(_is_plain(x, depth + 1) for x in v)
    return True


def check(scene) -> str:
    with deep():
        before = copy.deepcopy(scene)
        plain = _is_plain(scene)
    try:
        sent = host_check(scene, D)
        host_ok, host_err = True, None
    except ValueError as e:
        host_ok, host_err = False, e
        check_message(e, "host_check")
    with deep():
        assert same(scene, before), "host_check changed its input"
    if not plain:
        if not host_ok:
            return "host refused (numpy)"
        scene = sent                                # what would cross the link
    try:
        canon = S.validate(scene, D)
    except ValueError as e:
        check_message(e, "validate")
        assert not host_ok, "host_check accepted what validate refuses: %s" % e
        with deep():
            assert not plain or same(scene, before), "validate changed its input"
        return "refused"
    with deep():
        assert not plain or same(scene, before), "validate changed its input"
    if not host_ok:
        assert str(host_err).startswith("value is "), \
            "validate accepted what host_check refuses: %s" % host_err
        outcome = "accepted, too large for the link"
    else:
        outcome = "accepted"
        assert same(S.validate(sent, D), canon), "host_check's plain scene validates differently"
    again = S.validate(canon, D)
    assert same(again, canon), "validate(canonical) != canonical"
    sc = S.build(canon, D)
    amps = [sc.amp(p) for p in range(D["positions"])]
    assert all(type(a) is int and 0 <= a <= 65535 for a in amps), "amp() outside uint16"
    return outcome


@fuzzlib.fuzz_settings()
@given(inputs())
def test_scenes(case):
    scene, ops = case
    with fuzzlib.case(FUZZ_TARGET, lambda: "%s %s" % (ops, fuzzlib.short(scene, 200))) as s:
        with fuzzlib.watchdog(60, "a scene case"):
            try:
                outcome = check(scene)
            except Exception as e:                  # a broken property, or not a ValueError
                fuzzlib.allow_known(FUZZ_TARGET, e, lambda: "%s %s" % (ops, fuzzlib.short(scene)))
                outcome = "known bug"
        s.outcomes[outcome] += 1
