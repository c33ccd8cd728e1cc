"""Parameter-set validation: every bad value is refused with a message naming
the key, the value and the allowed range; the input is never changed."""
import copy
import math

import pytest

import texel
from texel.gen import params as P

GOOD = {"pitch_db": 6.3, "irregularity_db": -12.9}


def test_defaults_filled_and_input_untouched():
    src = dict(GOOD)
    keep = copy.deepcopy(src)
    v = texel.validate(src)
    assert src == keep
    assert v == {"pitch_db": 6.3, "irregularity_db": -12.9, "texel_samples": 50,
                 "length_samples": 9600, "quant_db": 0.0, "seed": 0, "gain": 1.0,
                 "v": 2, "band_limit_cpmm": None}       # no "v": format 2 (issue 32)


def test_ints_accepted_for_floats_and_converted():
    v = texel.validate({"pitch_db": 6, "irregularity_db": -10, "gain": 1})
    assert isinstance(v["pitch_db"], float) and isinstance(v["gain"], float)


@pytest.mark.parametrize("key,value,fragment", [
    ("pitch_db", float("nan"), "not finite"),
    ("pitch_db", float("inf"), "not finite"),
    ("irregularity_db", float("-inf"), "not finite"),
    ("pitch_db", 19.8, "out of range [-20.0, 19.747]"),
    ("pitch_db", -20.01, "out of range"),
    ("irregularity_db", 5.01, "out of range [-30.0, 5.0]"),
    ("irregularity_db", -31, "out of range"),
    ("quant_db", -1.0, "out of range"),
    ("gain", 1.5, "out of range [0.0, 1.0]"),
    ("gain", -0.1, "out of range"),
    ("texel_samples", 0, "out of range [1, 1048576]"),
    ("texel_samples", -5, "out of range"),
    ("length_samples", 0, "out of range"),
    ("length_samples", 10 ** 9, "out of range"),
    ("length_samples", 9600.0, "expected an int"),
    ("texel_samples", 50.5, "expected an int"),
    ("seed", -1, "out of range [0, 4294967295]"),
    ("seed", 2 ** 32, "out of range"),
    ("seed", True, "expected an int"),
    ("gain", False, "expected a number"),
    ("pitch_db", "6.3", "expected a number"),
    ("pitch_db", "__import__('os')", "expected a number"),
    ("pitch_db", [6.3], "expected a number"),
    ("pitch_db", None, "None is not allowed"),
    ("v", 3, "out of range [1, 2]"),
    ("v", 0, "out of range [1, 2]"),
    ("band_limit_cpmm", 100.0, "out of range"),
    ("band_limit_cpmm", 0.0, "out of range"),
])
def test_bad_values_name_key_value_and_range(key, value, fragment):
    bad = dict(GOOD, **{key: value})
    with pytest.raises(ValueError) as e:
        texel.validate(bad)
    msg = str(e.value)
    assert msg.startswith(key + ":"), msg
    assert fragment in msg, msg
    assert repr(value) in msg, msg


def test_unknown_key_lists_allowed():
    with pytest.raises(ValueError, match=r"unknown key 'pitch'.*allowed: pitch_db"):
        texel.validate({"pitch": 3, "irregularity_db": -10})


@pytest.mark.parametrize("missing", ["pitch_db", "irregularity_db"])
def test_required_keys(missing):
    d = dict(GOOD)
    del d[missing]
    with pytest.raises(ValueError, match="missing required key %r" % missing):
        texel.validate(d)


@pytest.mark.parametrize("bad", [None, [], "pitch_db=3", 42, (("pitch_db", 3),)])
def test_not_a_dict(bad):
    with pytest.raises(ValueError, match="must be a dict"):
        texel.validate(bad)


def test_limits_themselves_accepted():
    for key, (kind, default, lo, hi) in P.SPEC.items():
        for x in (lo, hi):
            texel.validate(dict(GOOD, **{key: x}))


def test_ragged_map_allowed_and_texel_count():
    v = texel.validate(dict(GOOD, length_samples=101, texel_samples=50))
    assert P.texel_count(v) == 3
    v = texel.validate(dict(GOOD, length_samples=100, texel_samples=30000))
    assert P.texel_count(v) == 1


def test_draws_without_v_say_which_format_replays_them():
    """No "v" is format 2, which draws from its seed: logged draws are refused
    with the way to replay them ("v": 1), not silently ignored."""
    with pytest.raises(ValueError, match=r"draws: replaying logged draws is format 1's \(v=1\)"):
        texel.make_plan(GOOD, (0.5, [0.0] * 192))


def test_render_rejects_before_any_work():
    with pytest.raises(ValueError, match="pitch_db"):
        texel.render(dict(GOOD, pitch_db=float("nan")))
    with pytest.raises(ValueError, match="engine: unknown engine 'gpu'"):
        texel.render(GOOD, engine="gpu")


@pytest.mark.parametrize("draws,fragment", [
    ((0.5, [0.0] * 10), "the map needs 192 texels"),
    ((1.5, [0.0] * 192), "u must be a number in [0, 1]"),
    ((0.5, [float("nan")] * 192), "finite"),
    ((0.5,), "expected (u, z_sequence)"),
    ((0.5, 7), "must be a sequence"),
])
def test_bad_draws(draws, fragment):
    with pytest.raises(ValueError) as e:
        texel.make_plan(dict(GOOD, v=1), draws)     # replayed draws are format 1's
    assert fragment in str(e.value)


def test_dx_and_nyquist_constants():
    assert texel.DX_MM == 0.0053
    assert math.isclose(texel.NYQUIST_CPMM, 94.3396, rel_tol=1e-5)
    # the pitch ceiling is the display's Nyquist pitch in dB (10*log10)
    assert abs(10 * math.log10(texel.NYQUIST_CPMM) - P.PITCH_DB_MAX) < 1e-3


# --- holes found by the build properties (tests/gen/test_build_property.py) ---
@pytest.mark.parametrize("key", ["pitch_db", "irregularity_db", "quant_db", "gain", "band_limit_cpmm"])
@pytest.mark.parametrize("value", [10 ** 400, -(10 ** 400), 2 ** 1024, 2 ** 62, -(2 ** 62)])
def test_huge_int_in_a_float_field_is_out_of_range(key, value):
    """Hole: validate({"pitch_db": 10**400, ...}) raised OverflowError (int
    too large to convert to float) on CPython, and MicroPython called the
    same value "not finite". Now: out of range, the value named, on both."""
    p = {"pitch_db": 6.0, "irregularity_db": -10.0, key: value}
    lo, hi = P.SPEC[key][2:]
    with pytest.raises(ValueError) as e:
        texel.validate(p)
    assert str(e.value) == "%s: a huge int (beyond 2^62) is out of range [%r, %r]" % (key, lo, hi)


WIDE = {"pitch_db": 6.3, "irregularity_db": 5.0, "texel_samples": 50, "length_samples": 500,
        "v": 1}                     # replayed draws are format 1's


@pytest.mark.parametrize("zs,fragment", [
    ([1e300] * 10, "z[0] must be a finite number in [-10.0, 10.0], got 1e+300"),     # OverflowError
    ([100.0] * 10, "got 100.0"),                  # 10**317: OverflowError / inf -> int
    ([0.0] * 9 + [-1e300], "z[9] must be a finite number in [-10.0, 10.0], got -1e+300"),   # pitch 0
    ([12.0] * 10, "got 12.0"),                    # 10^40 c/mm: beyond float32 on a board
    ([-13] * 10, "got -13"),                      # a subnormal float32 pitch
    ([10.000000000000002] * 10, "got 10.000000000000002"),
    ([1j] * 10, "got complex"),                   # TypeError in float()
    ([None] * 10, "got NoneType"),                # TypeError in float()
    (["1.5"] * 10, "got str"),
    ([True] * 10, "got True"),
    ([10 ** 400] * 10, "got a huge int (beyond 2^62)"),
    ([float("nan")] * 10, "got nan"),
    (set(range(10)), "z_sequence must be an indexable sequence"),                 # TypeError
    ({i: 0.0 for i in range(1, 11)}, "z_sequence must be an indexable sequence"),  # KeyError
])
def test_replayed_draws_out_of_range_refused(zs, fragment):
    """Hole: _check_draws accepted any finite z (and any object at all): the
    plan then raised OverflowError (z = 100 at sigma 3.16: 10**317), made a
    pitch of 0 and pitches_db() a "math domain error" (z = -1e300), and
    TypeError for complex/None elements or a set of draws."""
    with pytest.raises(ValueError) as e:
        texel.make_plan(WIDE, (0.5, zs))
    assert str(e.value).startswith("draws: ") and fragment in str(e.value), str(e.value)
