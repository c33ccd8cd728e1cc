"""Inputs a user can type (or a sweep can produce) that once ended in a
traceback, or that the Python API refused although they are plain numbers:

- a scene nested thousands of levels deep (RecursionError), a 5,000-digit
  integer (Python 3.11's int->str limit), in a scene file, a flag or the API;
- output files that cannot be written, found only after all the work;
- `texelpad tank` with values at the ends of the float range (ZeroDivision,
  overflow, an E12 search beyond the range);
- output piped to a reader that goes away (`| head`: BrokenPipeError);
- negative numbers as flag values (`--pitch-db -inf`, `-1e1`: argparse took
  them for flags);
- numpy numbers and arrays given to the Python API (np.linspace sweeps),
  converted exactly on the host; np.bool_ refused as True is.

Each CLI case: one line on stderr, a non-zero exit, no traceback.
"""
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import texel
import texelpad
from texelpad import cli
from texelpad.link import LiteralError, literal
from texelpad.link.protocol import MAX_DEPTH, plain
from texelpad.plate import tank
from support.cli import run_cli

ROOT = Path(__file__).resolve().parents[2]


def _run(argv, capsys):
    return run_cli(capsys, *argv)


def _one_line(err):
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


def _nested(depth, leaf=0):
    v = leaf
    for _ in range(depth):
        v = [v]
    return v


# --- literals: depth, huge integers ------------------------------------------------

def test_deep_nesting_is_refused_naming_the_path():
    scene = {"regions": [{"start_mm": 0, "end_mm": 1,
                          "texture": {"kind": "samples", "values": _nested(3000)}}]}
    with pytest.raises(LiteralError) as e:
        literal(scene)
    msg = str(e.value)
    assert msg.startswith("regions[0].texture.values[0][0]") and "nested more than" in msg
    assert len(msg) < 200


def test_depth_limit_is_exact():
    literal(_nested(MAX_DEPTH))
    with pytest.raises(LiteralError, match="nested more than %d levels" % MAX_DEPTH):
        literal(_nested(MAX_DEPTH + 1))


@pytest.mark.parametrize("n", [10 ** 5000, -10 ** 5000, 1 << 64, -(1 << 63) - 1],
                         ids=["10**5000", "-10**5000", "2**64", "-2**63-1"])
def test_huge_integers_are_refused(n):
    with pytest.raises(LiteralError) as e:
        literal({"regions": [{"texture": {"seed": n}}]})
    assert str(e.value).startswith("regions[0].texture.seed: an integer of about ")
    assert "64 bits" in str(e.value)


def test_64_bit_integers_cross():
    for n in ((1 << 64) - 1, -(1 << 63), 0):
        assert literal([n]) == "[%d]" % n


def test_huge_integer_key_is_refused_without_repr():
    with pytest.raises(LiteralError, match=r"key \(an integer of about 5,000 digits\)"):
        literal({10 ** 4999: 1})


# --- numpy on the host: converted exactly, before validation --------------------------

def test_numpy_scalars_become_plain_numbers_exactly():
    v = {"a": np.float64(6.3), "b": np.float32(0.1), "c": np.int64(-7), "d": np.uint64(2 ** 64 - 1),
         "e": np.int8(3), "f": np.float16(0.5), "g": np.bool_(True), np.str_("h"): np.str_("x")}
    p = plain(v)
    assert p == {"a": 6.3, "b": float(np.float32(0.1)), "c": -7, "d": 2 ** 64 - 1, "e": 3,
                 "f": 0.5, "g": True, "h": "x"}
    assert [type(p[k]) for k in "abcdefgh"] == [float, float, int, int, int, float, bool, str]
    assert p["b"] == 0.10000000149011612                     # the float32's own value
    assert literal(v) == repr(p)
    assert type(v["a"]) is np.float64                          # the input is not changed


def test_numpy_arrays_become_lists():
    a = np.linspace(0.0, 1.0, 5)
    assert plain({"values": a}) == {"values": [0.0, 0.25, 0.5, 0.75, 1.0]}
    assert plain((np.arange(3, dtype=np.uint16),)) == ([0, 1, 2],)
    assert plain(np.array([[1, 2], [3, 4]], dtype=np.int32)) == [[1, 2], [3, 4]]
    assert plain(np.array(2.5)) == 2.5                         # 0-d
    assert plain([np.float32(1.5)] * 2) == [1.5, 1.5]


@pytest.mark.parametrize("bad, where", [
    ({"a": np.float64("nan")}, "a: nan is not finite"),
    ({"a": np.float32("-inf")}, "a: -inf is not finite"),
    ({"a": np.array([0.0, np.inf])}, "a[1]: inf is not finite"),
    ({"a": np.complex128(1j)}, "a: complex128 values cannot be sent"),
    ({"a": np.array([1j])}, "a: ndarray values cannot be sent"),
    ({"a": np.datetime64("2026-01-01")}, "a: datetime64 values cannot be sent"),
])
def test_numpy_refusals_match_plain_ones(bad, where):
    with pytest.raises(LiteralError) as e:
        literal(bad)
    assert str(e.value).startswith(where), str(e.value)


def test_nan_refused_alike_as_numpy_and_float():
    msgs = []
    for nan in (float("nan"), np.float64("nan"), np.float32("nan")):
        with pytest.raises(LiteralError) as e:
            literal({"regions": [{"texture": {"pitch_db": nan}}]})
        msgs.append(str(e.value))
    assert len(set(msgs)) == 1


@pytest.mark.skipif(np.finfo(np.longdouble).nmant <= 52, reason="long double is float64 here")
def test_long_double_that_float64_cannot_hold_is_refused():
    assert plain(np.longdouble(0.5)) == 0.5
    with pytest.raises(LiteralError, match="cannot be sent exactly"):
        literal({"x": np.longdouble(1) / 3})


# --- scene files ---------------------------------------------------------------------

def test_scene_file_nested_3000_deep(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    f = tmp_path / "deep.json"
    f.write_text('{"regions": [{"start_mm": 0, "end_mm": 1, "texture": {"kind": "samples", '
                 '"values": ' + "[" * 3000 + "0" + "]" * 3000 + "}}]}")
    rc, out, err = _run(["demo", "--scene", str(f)], capsys)
    assert rc == 2 and out == ""
    assert "--scene" in _one_line(err) and "nested too deeply" in err


def test_scene_file_nested_100_deep_names_the_path(tmp_path, capsys):
    f = tmp_path / "deep.json"
    f.write_text(json.dumps({"regions": [{"start_mm": 0, "end_mm": 1, "texture": {
        "kind": "samples", "values": _nested(100)}}]}))
    rc, out, err = _run(["demo", "--scene", str(f)], capsys)
    assert rc == 2
    assert "--scene: regions[0].texture.values[0]" in _one_line(err) and "nested" in err


@pytest.mark.parametrize("digits, words", [(5000, "has 5,000 digits"),
                                           (30, "an integer of about 30 digits")])
def test_scene_file_huge_integer(tmp_path, capsys, digits, words):
    f = tmp_path / "big.json"
    f.write_text('{"regions": [{"start_mm": 0, "end_mm": 1, "texture": {"kind": "texel", '
                 '"pitch_db": 6, "irregularity_db": -10, "seed": %s}}]}' % ("9" * digits))
    rc, out, err = _run(["demo", "--scene", str(f)], capsys)
    assert rc == 2
    line = _one_line(err)
    assert "--scene" in line and words in line and len(line) < 300


# --- flags: huge integers, negative numbers -------------------------------------------

RENDER = ["render", "--pitch-db", "6", "--irregularity-db", "-10"]


def test_flag_with_5000_digits(capsys):
    rc, out, err = _run(RENDER + ["--seed", "9" * 5000], capsys)
    assert rc == 2
    line = _one_line(err)
    assert "--seed: invalid int value: '9999" in line and "(5,000 characters)" in line
    assert len(line) < 300


def test_flag_with_junk_is_shown_cut(capsys):
    rc, out, err = _run(RENDER + ["--seed", "x" * 5000], capsys)
    assert rc == 2
    line = _one_line(err)
    assert "--seed: invalid int value" in line and len(line) < 300


@pytest.mark.parametrize("value, words", [("-inf", "-inf is not finite"),
                                          ("-nan", "nan is not finite"),
                                          ("-Infinity", "-inf is not finite"),
                                          ("-1e9", "out of range")])
def test_negative_flag_values_reach_the_check(value, words, capsys):
    rc, out, err = _run(["render", "--pitch-db", value, "--irregularity-db", "-10"], capsys)
    assert rc == 2
    line = _one_line(err)
    assert "--pitch-db" in line and words in line, line


@pytest.mark.parametrize("value, want", [("-5", -5.0), ("-1e1", -10.0), ("-.5", -0.5),
                                         ("-5.", -5.0)])
def test_negative_flag_values_are_values(value, want):
    args = cli.build_parser(["render"]).parse_args(["render", "--pitch-db", value,
                                                    "--irregularity-db", value])
    assert args.pitch_db == want and args.irregularity_db == want


def test_negative_tank_quantity_is_one_line(capsys):
    rc, out, err = _run(["tank", "-L", "-1u", "-f", "34k"], capsys)
    assert rc == 2
    assert "--inductance" in _one_line(err) and "must be positive" in err


# --- output files: checked before the work --------------------------------------------

def _boom(*a, **k):
    raise AssertionError("the work ran although the output file cannot be written")


@pytest.mark.parametrize("argv, flag", [
    (["render", "--pitch-db", "6", "--irregularity-db", "-10", "--out", "{bad}/m.png"], "--out"),
    (["bench", "--json", "{bad}/b.json"], "--json"),
    (["bench-refresh", "--json", "{bad}/b.json"], "--json"),
    (["bench-link", "--json", "{bad}/b.json"], "--json"),
    (["demo", "--json", "{bad}/b.json"], "--json"),
    (["demo", "--out", "{bad}/d.png"], "--out"),
])
@pytest.mark.parametrize("bad", ["missing", "file"])
def test_unwritable_output_found_before_the_work(argv, flag, bad, tmp_path, capsys,
                                                 monkeypatch):
    import texelpad.bench.engines
    import texelpad.bench.link
    import texelpad.bench.refresh
    import texelpad.sim.virtual
    monkeypatch.setattr(texel, "render", _boom)
    monkeypatch.setattr(texelpad.bench.engines, "run", _boom)
    monkeypatch.setattr(texelpad.bench.refresh, "run", _boom)
    monkeypatch.setattr(texelpad.bench.link, "run", _boom)
    monkeypatch.setattr(texelpad.sim.virtual, "open_virtual", _boom)
    if bad == "missing":
        d = tmp_path / "no" / "such"
    else:
        d = tmp_path / "a-file"
        d.write_text("")
    rc, out, err = _run([a.replace("{bad}", str(d)) for a in argv], capsys)
    assert rc == 1 and out == ""
    line = _one_line(err)
    assert ("%s: cannot write" % flag) in line and str(d) in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ([] if bad == "missing" else ["a-file"])


@pytest.mark.parametrize("argv, flag", [
    (["bench", "--json", "b.txt"], "--json"),
    (["bench-refresh", "--json", "b.csv"], "--json"),
    (["demo", "--json", "d.png"], "--json"),
    (["render", "--pitch-db", "6", "--irregularity-db", "-10", "--out", "m.jpg"], "--out"),
])
def test_output_suffix_checked_before_the_work(argv, flag, tmp_path, capsys, monkeypatch):
    import texelpad.bench.engines
    import texelpad.bench.refresh
    import texelpad.sim.virtual
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(texel, "render", _boom)
    monkeypatch.setattr(texelpad.bench.engines, "run", _boom)
    monkeypatch.setattr(texelpad.bench.refresh, "run", _boom)
    monkeypatch.setattr(texelpad.sim.virtual, "open_virtual", _boom)
    rc, out, err = _run(argv, capsys)
    assert rc == 2 and "%s: unsupported file type" % flag in _one_line(err)
    assert list(tmp_path.iterdir()) == []


def test_output_into_a_directory_is_refused(tmp_path, capsys):
    d = tmp_path / "x.png"
    d.mkdir()
    rc, out, err = _run(RENDER + ["--out", str(d)], capsys)
    assert rc == 1 and "it is a directory" in _one_line(err) and out == ""


def test_check_output_leaves_no_probe(tmp_path):
    from texelpad.cli.files import check_output
    assert check_output("--out", str(tmp_path / "m.png"), (".png",)) == tmp_path / "m.png"
    assert list(tmp_path.iterdir()) == []


def test_render_still_writes(tmp_path, capsys):
    out = tmp_path / "m.npy"
    rc, so, err = _run(RENDER + ["--out", str(out)], capsys)
    assert rc == 0 and out.exists() and "wrote" in so


# --- tank: the ends of the float range ------------------------------------------------

@pytest.mark.parametrize("argv", [
    ["-L", "5e-324", "-C", "5e-324"],
    ["-L", "1.7e308", "-C", "5e-324"],
    ["-L", "1e300", "-f", "1e300"],
    ["--piezo", "1", "-L", "1e-300", "-f", "1e300"],
    ["--piezo", "5e-324", "-f", "1.7e308"],
    ["-L", "390u", "-f", "34k", "--bus-volts", "1e300", "--q", "1e300"],
    ["-L", "390u", "-f", "34k", "--bus-volts", "1e200", "--q", "1e200", "--drive", "bridge"],
])
def test_tank_beyond_float_range_is_one_line(argv, capsys):
    for extra in ([], ["--json"]):
        rc, out, err = _run(["tank"] + argv + extra, capsys)
        assert rc == 2 and out == ""
        line = _one_line(err)
        assert "cannot compute with these values" in line and "too extreme" in line, line


@pytest.mark.parametrize("argv, words", [
    (["-L", "1e-300", "-C", "1e-300"], "f = 1.5915e+299 Hz"),     # L*C underflows to 0
    (["-L", "1e300", "-C", "1e300"], "f = 1.5915e-301 Hz"),
    (["--piezo", "1e-300", "-f", "1e300"], "L = 2.533e-302 H"),
    (["--piezo", "1e-300", "-L", "1e300"], "resonates at 159.15 mHz"),
    (["--piezo", "1e300", "-L", "1e-300", "-f", "1e3"], "in series with the piezo"),
])
def test_tank_extreme_but_representable(argv, words, capsys):
    rc, out, err = _run(["tank"] + argv, capsys)
    assert rc == 0 and err == ""
    assert words in out and max(len(l) for l in out.splitlines()) < 400
    rc, out, err = _run(["tank"] + argv + ["--json"], capsys)
    assert rc == 0
    json.loads(out, parse_constant=lambda c: pytest.fail("non-finite %s in JSON" % c))


def test_tank_library_raises_value_error_not_arithmetic():
    for f, args in [(tank.resonant_frequency, (5e-324, 5e-324)),
                    (tank.capacitance_for, (1e300, 1e300)),
                    (tank.inductance_for, (1e-300, 1e-300)),
                    (tank.piezo_voltage, (1e300, 1e300)),
                    (tank.nearest_e12, (1.7e308, 1))]:
        with pytest.raises(ValueError):
            f(*args)
    assert tank.resonant_frequency(1e-300, 1e-300) == pytest.approx(1 / (2 * math.pi * 1e-300))
    # sqrt(L)/sqrt(C): L/C alone would overflow
    assert tank.Tank(1.7e308, 1e-300, 1.0).impedance_ohm == pytest.approx(1.3038e304, rel=1e-4)
    assert tank.nearest_e12(1.7e308, -1) == 1.5e308
    assert tank.nearest_e12(5e-324) > 0


def test_format_quantity_beyond_the_prefixes():
    assert tank.format_quantity(1e-300, "H") == "1e-300 H"
    assert tank.format_quantity(1.5915494e299, "Hz", 5) == "1.5915e+299 Hz"
    assert tank.format_quantity(3.9e-4, "H") == "390 \u00b5H"        # unchanged


# --- a reader that goes away ------------------------------------------------------------

def _env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "device"), str(ROOT / "host"),
                                         env.get("PYTHONPATH", "")])
    return env


def test_closed_stdout_exits_1_quietly(tmp_path):
    """`texelpad tank ... | head -0`: the reader is gone before the output;
    exit 1, nothing on stderr (the Python docs' recipe), no traceback."""
    p = subprocess.Popen([sys.executable, "-m", "texelpad.cli", "tank", "-L", "390u", "-f", "34k",
                          "--json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=_env(),
                         cwd=str(tmp_path))
    p.stdout.close()                               # before the child has written anything
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 1
    assert err == "", err


def test_broken_pipe_not_on_stdout_is_one_line(capsys, monkeypatch):
    import texelpad.cli.tank as tank_cmd

    def broken(args):
        raise BrokenPipeError(32, "Broken pipe")
    monkeypatch.setattr(tank_cmd, "cmd_tank", broken)
    rc, out, err = _run(["tank", "-L", "390u", "-f", "34k"], capsys)
    assert rc == 1 and "broken pipe" in _one_line(err)


# --- the Python API on the virtual board: numpy numbers -------------------------------

@pytest.fixture(scope="module")
def board():
    from texelpad.sim.virtual import VirtualBoard
    with VirtualBoard(image="source") as v:
        with texelpad.connect(v.port) as b:
            b.start("virtual", None, realtime=True)
            yield b


@pytest.mark.vboard
def test_push_texel_takes_a_linspace_sweep(board):
    for pd in np.linspace(0.0, 6.3, 4):
        st = board.push_texel({"pitch_db": pd, "irregularity_db": np.float32(-12.5),
                               "seed": np.int64(7)})
        reg = st["scene"]["regions"][0]
        assert (reg["pitch_db"], reg["irregularity_db"], reg["seed"]) == (float(pd), -12.5, 7)
    assert board.scene_source()["regions"][0]["texture"]["pitch_db"] == 6.3


@pytest.mark.vboard
@pytest.mark.parametrize("np_value, py_value", [(np.float64("nan"), float("nan")),
                                                (np.float32("inf"), float("inf")),
                                                (np.bool_(True), True),
                                                (np.int64(-1), -1)])
def test_numpy_refused_exactly_as_plain(board, np_value, py_value):
    src0 = board.scene_source()
    errors = []
    for v in (np_value, py_value):
        params = {"pitch_db": 3.0, "irregularity_db": -10.0, "seed": v}
        with pytest.raises(ValueError) as e:
            board.push_texel(params)
        errors.append((type(e.value), str(e.value)))
        assert type(params["seed"]) is type(v)           # the caller's dict is not changed
    assert errors[0] == errors[1]
    assert errors[0][1].startswith("regions[0].texture.seed: ")
    assert board.scene_source() == src0                  # still playing what it played


@pytest.mark.vboard
def test_push_scene_with_numpy_array_and_render_u16(board):
    vals = np.linspace(0.0, 1.0, 64, dtype=np.float32)
    st = board.push({"regions": [{"start_mm": np.float64(0), "end_mm": np.float64(101.76),
                                  "texture": {"kind": "samples", "values": vals}}]})
    reg = st["scene"]["regions"][0]
    assert reg["kind"] == "samples" and reg["values"] == 64
    p = {"pitch_db": np.float64(3.0), "irregularity_db": np.float64(-10.0),
         "length_samples": np.int32(500), "seed": np.uint8(9)}
    got = board.render_u16(p, engine="int")
    want = np.asarray(texel.render_u16({"pitch_db": 3.0, "irregularity_db": -10.0,
                                        "length_samples": 500, "seed": 9}, engine="int"))
    assert np.array_equal(got, want)


@pytest.mark.vboard
def test_api_refuses_deep_and_huge_before_sending(board):
    sent = board.link.sent
    with pytest.raises(LiteralError, match="nested more than"):
        board.push({"regions": [{"start_mm": 0, "end_mm": 1, "texture": {
            "kind": "samples", "values": _nested(3000)}}]})
    with pytest.raises(LiteralError, match="seed: an integer of about 5,000 digits"):
        board.push_texel({"pitch_db": 3.0, "irregularity_db": -10.0, "seed": 10 ** 4999})
    with pytest.raises(LiteralError, match="seed: an integer of about"):
        board.render_u16({"pitch_db": 3.0, "irregularity_db": -10.0, "seed": 10 ** 4999})
    assert board.link.sent - sent < 1000    # two status() requests, neither payload (> 5 KB)
