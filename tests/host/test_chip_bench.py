"""`texelpad bench-refresh --chip rp2040 --no-unix` on the emulated Pico
(../shared/instruments/rp2emu; texelpad/bench/chip.py): one short run - the
shortest soak - that goes through every measurement (the refresh's cost with
and without its interrupt, the finger held at known ADC values, host pushes,
the carrier on the pin probe) and checks the figures are there and make sense.
No assertion depends on a timing value: the figures themselves are the
benchmark's (docs/runtime.md), printed here with pytest -s."""
from __future__ import annotations

import io
import json
from contextlib import redirect_stderr, redirect_stdout

import pytest

from texelpad import cli
from texelpad.sim.emulated import why_not

pytestmark = [pytest.mark.instruments, pytest.mark.slow]


def test_bench_refresh_on_the_emulated_chip(tmp_path):
    why = why_not()
    if why:
        pytest.skip(why)
    out = tmp_path / "chip.json"
    so, se = io.StringIO(), io.StringIO()
    with redirect_stdout(so), redirect_stderr(se):
        rc = cli.main(["bench-refresh", "--chip", "rp2040", "--no-unix", "--soak-seconds", "0.3",
                       "--json", str(out)])
    stdout, stderr = so.getvalue(), se.getvalue()
    print("\n" + stdout)
    assert rc == 0, stdout + stderr
    assert "Traceback" not in stdout + stderr
    doc = json.loads(out.read_text())
    assert doc["failed"] == [] and doc["refresh"] == []          # the unix port was left out
    chip = doc["chip"]
    # the refresh runs as the PWM-wrap interrupt (hw/rp2.py), the viper body itself
    assert chip["mode"] == "viper-irq" and chip["irq_source"].startswith("PWM slice 3 wrap")
    assert chip["machine_freq"] == 125_000_000 and chip["period_us"] == 120
    irq = chip["irq"]
    assert len(irq["reps"]) == 8 and all(r["refreshes"] > 100 for r in irq["reps"])
    assert all(r["on_us"] > r["off_us"] for r in irq["reps"])    # the interrupt took time
    holds = chip["holds"]
    assert len(holds["rows"]) == 12
    assert holds["positions_exact"]            # the held finger reads the position it means
    assert holds["cc_equals_law"] and holds["cc_equals_duty"]   # CC = DutyLaw(scene's amplitude)
    assert {r["region"] for r in holds["rows"]} == {"reference", "texel"}
    soak = chip["soak"]
    assert soak["pushes"] >= 1 and soak["refreshes"] > 0 and soak["faults"] == 0
    probe = chip["probe"]
    assert probe["period_cycles"] == chip["pwm_top"] + 1        # 125 MHz / 3,676 counts
    assert 0.0 < probe["duty_mean"] < 0.5 and probe["duty_max"] <= 0.5   # duty_cap 0.5
    assert doc["chip_opcount_check"]["path"] == "viper-irq"
    assert "EMULATED CHIP: RP2040" in stdout and "op-count ESTIMATE for viper-irq" in stdout
