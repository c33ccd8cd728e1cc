"""`texelpad bench-refresh`: runs the device runtime under the MicroPython unix
port with a short --seconds, reports every figure in its table and JSON, skips
the fused viper refresh cleanly when it is absent, and makes its RP2040
estimate from the op counts by the stated formula. No assertion here depends
on a timing value."""
import io
import json
import math
import re
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import pytest

from texelpad import cli, toolchain
from texelpad.bench import refresh as rb

HAVE_MP = toolchain.micropython() is not None
needs_mp = pytest.mark.skipif(not HAVE_MP, reason="micropython (unix port) not installed")
VIPER_SOURCE = (Path(rb.texel.__file__).resolve().parent / "refresh_viper.py").is_file()
SCENES = ["split", "texel", "reference", "regions16", "constant"]


def _strict_json(path):
    def bad(c):
        raise ValueError("non-JSON constant %s" % c)
    return json.loads(Path(path).read_text(), parse_constant=bad)


def _main(argv):
    so, se = io.StringIO(), io.StringIO()
    with redirect_stdout(so), redirect_stderr(se):
        rc = cli.main(argv)
    return rc, so.getvalue(), se.getvalue()


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("refresh") / "refresh.json"
    rc, stdout, stderr = _main(["bench-refresh", "--seconds", "0.05", "--json", str(out)])
    return rc, stdout, stderr, _strict_json(out)


@needs_mp
def test_exit_and_progress(run):
    rc, stdout, stderr, doc = run
    assert rc == 0, stdout + stderr
    assert "Traceback" not in stdout + stderr
    assert "bench-refresh: micropython" in stderr
    assert "bench-refresh: Python refresh (python)" in stderr
    assert "bench-refresh: wrote" in stderr
    assert doc["failed"] == []


@needs_mp
def test_json_header(run):
    rc, stdout, stderr, doc = run
    assert doc["schema"] == rb.SCHEMA
    assert doc["seconds"] == 0.05
    assert doc["budget"] == {"refresh_hz": 8333, "period_us": 120, "goal_us": 10.0}
    sw = doc["swipe"]
    assert sw["batch"] == 100 and sw["period_us"] == 120
    assert sw["keyframes_ms_mm"][0] == [0, 5.0] and 0 < sw["lifted_fraction"] < 0.1
    m = doc["machine"]
    assert m["micropython"]["heap"] == rb.MP_HEAP and m["micropython"]["version"]
    cal = doc["unix_calibration_us"]
    for key in ("int_op_us", "float_op_us", "call_us", "builtin_call_us",
                "int_builtin_call_us"):
        assert key in cal


def _stat_ok(st, batch=100):
    assert st["batch"] == batch and st["batches"] >= 5
    assert st["best_us"] <= st["median_us"] <= st["worst_us"]
    assert st["best_us"] <= st["mean_us"] <= st["worst_us"]


@needs_mp
def test_refresh_rows(run):
    rc, stdout, stderr, doc = run
    rows = {r["variant"]: r for r in doc["refresh"]}
    py = rows["python"]
    assert py["mode"] == "python" and py["callback"] == "Refresh.step"
    _stat_ok(py["stat"])
    assert len(py["batch_us"]) == len(py["empty_us"]) == py["stat"]["batches"]
    # every timed refresh ran on the virtual board, none failed
    assert py["refreshes"] == 100 * py["stat"]["batches"]
    assert py["faults"] == 0 and py["virtual_s"] > 0
    assert py["minus_adc_median_us"] is not None
    assert py["budget_pct"] == pytest.approx(100 * py["stat"]["median_us"] / 120)
    assert py["meets_goal"] == (py["stat"]["median_us"] <= 10.0)
    if doc["viper_refresh"]["how"]:
        vp = rows["viper"]
        assert vp["mode"].startswith("viper") and vp["callback"] == "FastRefresh.step"
        _stat_ok(vp["stat"])
        assert vp["refreshes"] == 100 * vp["stat"]["batches"] and vp["faults"] == 0
    else:
        assert "viper" not in rows
        assert [s["variant"] for s in doc["skipped"]] == ["viper"]


@needs_mp
def test_components(run):
    rc, stdout, stderr, doc = run
    comps = {(c["variant"], c["name"]): c for c in doc["components"]}
    for name in ("sensor.read", "virtual_adc", "scene.amp", "law.duty", "hw.set_duty",
                 "step_body"):
        c = comps[("python", name)]
        assert c["what"]
        _stat_ok(c["stat"])
    if doc["viper_refresh"]["how"]:
        _stat_ok(comps[("viper", "viper_core")]["stat"])


@needs_mp
def test_scenes_memory_and_push(run):
    rc, stdout, stderr, doc = run
    scenes = {s["key"]: s for s in doc["scenes"]}
    assert list(scenes) == SCENES
    # Scene.nbytes: 2 bytes per buffered position, 8 per texel of a texel
    # region played from its plan, + 16 bytes per table row
    assert scenes["split"]["nbytes"] == 2 * 9600 + 8 * 192 + 16 * 3
    assert scenes["texel"]["nbytes"] == 8 * 384 + 16 * 2
    assert scenes["reference"]["nbytes"] == 2 * 19200 + 16 * 2
    assert scenes["constant"]["nbytes"] == 32 and scenes["constant"]["buffer_bytes"] == 0
    assert scenes["regions16"]["regions"] == 16
    assert scenes["regions16"]["table_bytes"] == 16 * 17
    variants = ["python"] + (["viper"] if doc["viper_refresh"]["how"] else [])
    for s in scenes.values():
        assert s["nbytes"] == s["buffer_bytes"] + s["table_bytes"]
        # the heap holds at least the buffers, plus the objects around them
        assert s["mem_alloc_delta"] >= s["buffer_bytes"]
        assert s["build_churn_bytes"] is not None and s["build_churn_bytes"] > 0
        assert sorted(s["push"]) == sorted(variants)
        for p in s["push"].values():
            assert len(p["runs"]) == 3
            for r in p["runs"]:
                assert set(r) == {"validate_us", "push_us", "build_us", "swap_us",
                                  "scene_bytes"}
                assert r["scene_bytes"] == s["nbytes"]
            assert p["rest_us"] == pytest.approx(
                p["push_us"] - p["validate_us"] - p["build_us"] - p["swap_us"])


@needs_mp
def test_estimate_and_check(run):
    rc, stdout, stderr, doc = run
    est = doc["rp2040_estimate"]
    assert "ESTIMATE" in est["label"]
    assert "16 us" in est["formula"] and "0.27 us" in est["formula"]
    costs = est["costs_us"]
    assert costs["F"] == 16.0 and costs["V"] == 0.27
    assert costs["Vop"] == pytest.approx(0.27 / 19)
    paths = {p["path"]: p for p in est["paths"]}
    assert "python" in paths
    if VIPER_SOURCE:
        assert {"viper", "viper-irq"} <= set(paths)
    for p in paths.values():
        want = sum(p["counts"][k] * costs[k] for k in rb.CLASSES)
        assert p["est_us"] == pytest.approx(want)
        assert p["meets_goal"] == (p["est_us"] <= 10.0)
    names = [c["name"] for c in doc["unix_check"]]
    assert "Refresh.step with stub parts" in names and "law.duty" in names
    for c in doc["unix_check"]:
        assert c["ratio"] == pytest.approx(c["predicted_us"] / c["measured_us"])


@needs_mp
def test_table(run):
    rc, stdout, stderr, doc = run
    lines = stdout.splitlines()
    assert lines[0].startswith("texelpad bench-refresh:")
    for head in ("refresh (split screen, swipe)", "component (per call)", "scene",
                 "ESTIMATE, not a measurement", "path"):
        assert any(l.startswith(head) for l in lines), head
    # every table: a header, then a dashed rule with one run of dashes per column
    rules = [i for i, l in enumerate(lines) if l and set(l) <= {"-", " "} and "--" in l]
    assert len(rules) >= 4
    for i in rules:
        heads = re.split(r" {2,}", lines[i - 1].strip())
        assert len(lines[i].split()) == len(heads) >= 5
        assert len(lines[i + 1].rstrip()) <= len(lines[i])
    for label in ("split screen (study)", "full-screen texel", "full-screen reference",
                  "16 small regions", "constant only", "law.duty", "scene.amp"):
        assert label in stdout
    assert re.search(r"^python +Refresh\.step", stdout, re.M)
    assert "* est = " in stdout


@needs_mp
def test_without_the_viper_refresh(monkeypatch, tmp_path):
    """No texel/runtime/refresh_viper.py in the device copy: the viper variant is
    skipped with its reason, everything else is measured."""
    stage = rb._stage

    def stage_without(tmp):
        script = stage(tmp)
        (tmp / "texel" / "runtime" / "refresh_viper.py").unlink(missing_ok=True)
        return script
    monkeypatch.setattr(rb, "_stage", stage_without)
    res = rb.run(0.02)
    assert res.failed == []
    assert [r.variant for r in res.refresh] == ["python"]
    assert res.skipped and res.skipped[0]["variant"] == "viper"
    assert "refresh_viper" in res.skipped[0]["reason"]
    assert all(c.variant == "python" for c in res.components)
    assert all(list(s.push) == ["python"] for s in res.scenes)
    assert "skipped: viper" in rb.table(res)


def test_without_micropython(monkeypatch, tmp_path):
    monkeypatch.setattr(toolchain, "micropython", lambda: None)
    out = tmp_path / "r.json"
    rc, stdout, stderr = _main(["bench-refresh", "--seconds", "0.01", "--quiet",
                                "--json", str(out)])
    assert rc == 1
    assert "FAILED: micropython" in stdout
    doc = _strict_json(out)
    assert doc["refresh"] == [] and doc["failed"][0]["runtime"] == "micropython"
    # the estimate is still made (bench_model's default ratios)
    assert [p["path"] for p in doc["rp2040_estimate"]["paths"]][0] == "python"
    assert "default" in doc["rp2040_estimate"]["costs_source"]


def test_micropython_failure_is_reported(monkeypatch, tmp_path):
    fake = tmp_path / "micropython"
    fake.write_text("#!/bin/sh\necho 'Traceback (most recent call last):'\n"
                    "echo 'MemoryError: boom'\nexit 1\n")
    fake.chmod(0o755)
    monkeypatch.setattr(toolchain, "micropython", lambda: str(fake))
    res = rb.run(0.01)
    assert res.failed and "MemoryError: boom" in res.failed[0]["reason"]
    assert res.estimates and "FAILED: micropython" in rb.table(res)


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "x"])
def test_bad_seconds(value, capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["bench-refresh", "--seconds", value])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "--seconds" in err and "Traceback" not in err


def test_json_unwritable(monkeypatch, tmp_path):
    monkeypatch.setattr(toolchain, "micropython", lambda: None)
    rc, stdout, stderr = _main(["bench-refresh", "--quiet", "--json",
                                str(tmp_path / "no" / "such" / "dir.json")])
    assert rc == 1 and "--json: cannot write" in stderr


def test_stat_from_batches():
    st = rb.Stat.from_batches([300, 500, 400], [100, 100, 120], 100)
    assert st.loop_us == 1.0
    assert (st.best_us, st.median_us, st.worst_us) == (2.0, 3.0, 4.0)
    assert st.mean_us == 3.0 and st.batches == 3 and st.batch == 100
    with pytest.raises(rb.RefreshBenchError):
        rb.Stat.from_batches([], [], 100)


def test_model_paths_and_costs():
    costs, note = rb.rp2040_costs({"float_op_us": 0.04, "int_op_us": 0.01, "call_us": 0.04,
                                   "builtin_call_us": 0.04, "int_builtin_call_us": 0.02})
    assert costs["I"] == pytest.approx(4.0) and costs["C"] == pytest.approx(16.0)
    assert costs["N"] == pytest.approx(8.0) and costs["Vop"] == pytest.approx(0.27 / 19)
    assert "this run" in note
    rows = {r.path: r for r in rb.estimates(costs, True)}
    py = rows["python"]
    # the Python refresh: every part of the hot path once
    assert py.counts == rb._sum("dispatch", "step", "sensor.read", "adc_rp2", "scene.amp",
                                "law.duty", "set_duty_rp2")
    assert py.counts["us"] == rb.ADC_CONVERSION_US == py.fixed_us
    assert py.est_us == pytest.approx(sum(py.counts[k] * costs[k] for k in rb.CLASSES))
    assert rows["viper-irq"].counts["Vop"] == 146 + 39        # the fused body + its register work
    assert [r.path for r in rb.estimates(costs, False)] == ["python"]
    # the unix check prices the same counts with the unix costs
    cal = {"float_op_us": 0.04, "int_op_us": 0.01, "call_us": 0.04, "builtin_call_us": 0.04,
           "int_builtin_call_us": 0.02, "viper_iteration_us": 0.0038}
    comp = rb.ComponentRow("python", "law.duty", "", rb.Stat(0.2, 0.3, 0.1, 0.2, 5, 100, 0.0))
    (chk,) = rb.unix_checks(cal, [comp])
    assert chk.name == "law.duty"
    assert chk.predicted_us == pytest.approx(0.04 + 16 * 0.01)
    assert chk.ratio == pytest.approx(chk.predicted_us / 0.2)
    assert math.isfinite(chk.ratio)


# --- --chip rp2040 (texelpad/bench/chip.py): the parts that need no emulator ----------
# (the emulated run itself: tests/host/test_chip_bench.py, marked instruments and slow)

@pytest.mark.parametrize("flags", [["--no-unix"], ["--soak-seconds", "1"]])
def test_chip_only_flags_need_chip(flags, capsys):
    rc, stdout, stderr = _main(["bench-refresh", "--quiet"] + flags)
    assert rc == 2 and "only with --chip rp2040" in stderr and "Traceback" not in stderr


def test_chip_hold_counts_mean_whole_positions():
    from texel.runtime import boards
    from texelpad.bench import chip
    board = boards.load("pico")
    sensor, positions = board["sensor"], board["display"]["positions"]
    holds = chip.hold_counts(sensor, positions)
    assert len(holds) == len(chip.HOLD_TARGETS)
    for c, target in zip(holds, chip.HOLD_TARGETS):
        p = chip.ideal_position(c, sensor, positions)
        assert abs(p - round(p)) < 0.1 and abs(p - target) < 100
    assert chip.raw16(0xFFF) == 0xFFFF and chip.raw16(1) == 0x10     # rp2's read_u16 scaling
    js = chip.finger_js(holds)
    assert js.startswith("(ch, t) =>") and ", ".join(map(str, holds)) in js


def test_chip_probe_line_and_opcount_check():
    from texelpad.bench import chip
    text = ("probe GPIO16: 33603.7 Hz, duty mean 0.183, min 0.000, max 0.500, edges 27848, "
            "most common period 3676 cycles = 34004.4 Hz (99.7 % of periods)\n"
            "emulated_seconds=13.362374 cycles=1670296742 wall_seconds=30.01\n")
    p = chip.parse_probes(text)[16]
    assert p["period_cycles"] == 3676 and p["carrier_hz"] == 34004.4
    assert (p["duty_min"], p["duty_max"], p["period_share_pct"]) == (0.0, 0.5, 99.7)
    costs, _ = rb.rp2040_costs(None)
    est = rb.estimates(costs, True)
    res = {"mode": "viper-irq", "irq": {"median_us": 8.0}}
    chk = chip.opcount_check(res, est)
    want = next(e.est_us for e in est if e.path == "viper-irq")
    assert chk["estimate_us"] == want and chk["error_pct"] == pytest.approx(100 * (want / 8 - 1))
    assert chip.opcount_check({"mode": "python"}, est) is None          # nothing measured
