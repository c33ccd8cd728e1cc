"""`texelpad bench-refresh --chip rp2040`: the refresh measured on the emulated
Raspberry Pi Pico (../shared/instruments/rp2emu: rp2040js running the real
MicroPython v1.28 firmware, time from cycle counts; texelpad.sim.emulated).

One emulator session on a pty, as `texelpad bench-link --chip rp2040` runs it:
boot, deploy the image (armv6m .mpy), start board file 'pico' playing the
study's split screen (texel.app.DEFAULT_SCENE), send
bench/device/rp2_chip_bench.py to the board's REPL and call its functions:

- refresh cost, IRQ entry and exit included: a viper busy loop of a fixed
  number of iterations is timed with the chip's clock while the refresh
  interrupt runs and again with it stopped; (on - off) / refreshes in the
  window is what one refresh takes from the code it interrupts - the
  hardware's exception entry and exit, the firmware's dispatch, the refresh
  itself. (The refresh's own worst_us is read inside it, so it misses the
  dispatch.) rp2040js counts no cycles for the exception entry and exit
  themselves (a Cortex-M0+ takes about 30): printed beside the figure.
- amplitude at the finger: the finger (rp2emu's --adc-js, FINGER_JS) sweeps
  end to end and back in 2 s, then holds still at HOLDS ADC values for 50 ms
  each, every 2.6 s of emulated time. At 40 ms into each hold the board reads
  position, amplitude, duty and the PWM slice's CC register; the host
  compares them with the scene's map at the position the ADC value means
  (the same scene built here, texel.runtime.scene) and the duty law in
  floats (texel.runtime.duty.duty_fraction): error in PWM steps.
- rate and overruns: for >= soak seconds of emulated time the host pushes
  full-screen texel textures (Board.push_texel, as bench-link) while the
  finger sweeps; refreshes, overruns and worst_us from the board's own
  counters over that window, against the refreshes the period promises.
- carrier: the emulator's pin probe (--probe) on the carrier pin, printed
  when the emulator stops: its most common period (the carrier's own) and
  duty.

The emulated chip has no flash wait states and no XIP cache (rp2emu's README):
the refresh runs from RAM (viper code), so that does not flatter it.
"""
from __future__ import annotations

import re
import statistics
import time
from typing import Any, Callable

from .engines import DEVICE_SCRIPTS

Progress = Callable[[str], None]

CPU_HZ = 125_000_000
BOARD = "pico"
# a Cortex-M0+ takes 15 cycles to enter an exception with zero wait state
# memory (ARM's interrupt latency figure) and about as many to return;
# rp2040js counts none (cortex-m0-core.js exceptionEntry/exceptionReturn)
EXCEPTION_CYCLES = 30

# The finger, as rp2emu's --adc-js function of emulated seconds since power-on
# (12-bit counts on ADC channel 0 = GPIO26): every CYCLE_S a sweep from end to
# end and back (SWEEP_S, texelpad.sim.emulated.FINGERS["sweep"]), then a hold
# of HOLD_S at each of the hold counts.
CYCLE_S = 2.6
SWEEP_S = 2.0
HOLD_S = 0.05
SAMPLE_AT_S = 0.04          # into each hold: the filter has settled (see _holds)
HOLD_TARGETS = (300, 1900, 3500, 5100, 6700, 8300, 9900, 11500, 13100, 14700, 16300,
                17900)      # display positions, spread over both halves of the split screen
CHIP_SOAK_S = 10.0
IRQ_SPIN = 300_000          # busy-loop iterations per window: ~29 ms on the chip
IRQ_REPS = 8                # windows, IRQ_GAP_MS apart: spread over one finger cycle
IRQ_GAP_MS = 250


class ChipBenchError(RuntimeError):
    """The emulated chip could not be run or answered something unexpected."""


def raw16(count12: int) -> int:
    """machine.ADC.read_u16 of a 12-bit RP2040 reading (rp2: raw << 4 | raw >> 8)."""
    return (count12 << 4) | (count12 >> 8)


def ideal_position(count12: int, sensor: dict[str, Any], positions: int) -> float:
    """The display position an ADC reading means, in floats: the board file's
    two-point calibration (texel.runtime.sensor), unclamped."""
    r0, r1 = sensor["raw_at_start"], sensor["raw_at_end"]
    return (raw16(count12) - r0) * (positions - 1) / (r1 - r0)


def hold_counts(sensor: dict[str, Any], positions: int) -> list[int]:
    """One 12-bit ADC count near each HOLD_TARGETS position whose ideal
    position is within 0.1 of an integer: the sensor's rounding to a position
    is then unambiguous (a map can change completely from one position to the
    next, so the comparison must be at the position the finger means)."""
    out = []
    for target in HOLD_TARGETS:
        best = None
        for c in range(4096):
            p = ideal_position(c, sensor, positions)
            if abs(p - round(p)) < 0.1 and 0 <= p <= positions - 1:
                if best is None or abs(p - target) < abs(ideal_position(best, sensor,
                                                                        positions) - target):
                    best = c
        if best is None:
            raise ChipBenchError("no ADC count holds the finger near position %d" % target)
        out.append(best)
    return out


def finger_js(holds: list[int]) -> str:
    """The --adc-js function: sweep, then the holds, every CYCLE_S."""
    return ("(ch, t) => { if (ch !== 0) return 0; const u = t %% %r; "
            "if (u < %r) return Math.round(125 + 3812 * (1 - Math.abs(u - 1))); "
            "const k = Math.min(%d, Math.floor((u - %r) / %r)); return [%s][k]; }"
            % (CYCLE_S, SWEEP_S, len(holds) - 1, SWEEP_S, HOLD_S,
               ", ".join(str(c) for c in holds)))


_PROBE = re.compile(r"probe GPIO(\d+): ([\d.]+) Hz, duty mean ([\d.]+), min ([\w.]+), "
                    r"max ([\w.]+), edges (\d+)(?:, most common period (\d+) cycles = "
                    r"([\d.]+) Hz \(([\d.]+) % of periods\))?")


def parse_probes(text: str) -> dict[int, dict[str, Any]]:
    """rp2emu's probe summary lines (printed when it stops), per GPIO."""
    out = {}
    for m in _PROBE.finditer(text):
        out[int(m.group(1))] = {
            "mean_hz": float(m.group(2)), "duty_mean": float(m.group(3)),
            "duty_min": float(m.group(4)) if m.group(4) != "nan" else None,
            "duty_max": float(m.group(5)) if m.group(5) != "nan" else None,
            "edges": int(m.group(6)),
            "period_cycles": int(m.group(7)) if m.group(7) else None,
            "carrier_hz": float(m.group(8)) if m.group(8) else None,
            "period_share_pct": float(m.group(9)) if m.group(9) else None,
            "line": m.group(0)}
    return out


def _say(progress: Progress | None) -> Progress:
    return progress or (lambda m: None)


def run(soak_s: float = CHIP_SOAK_S, irq_reps: int = IRQ_REPS,
        progress: Progress | None = None, flash: str | None = None) -> dict[str, Any]:
    """The whole chip measurement (module docstring); a dict of figures.
    Raises ChipBenchError (or the link's errors) when the chip cannot be run."""
    from ..sim.emulated import EmulatedPico, why_not
    from ..link.board import connect
    from ..deploy.install import deploy
    from texel.runtime import boards
    why = why_not()
    if why:
        raise ChipBenchError(why)
    say = _say(progress)
    board = boards.load(BOARD)
    sensor, display = board["sensor"], board["display"]
    pin = int(board["carrier"]["pins"][0])
    holds = hold_counts(sensor, display["positions"])
    res: dict[str, Any] = {"chip": "rp2040", "board": BOARD, "cpu_hz": CPU_HZ,
                           "finger_js": finger_js(holds), "probe_gpio": pin,
                           "soak_s_asked": soak_s}
    t_wall = time.monotonic()
    emu = EmulatedPico(flash, extra_args=("--adc-js", res["finger_js"], "--probe", str(pin)))
    summary = ""
    try:
        say("booting the emulated RP2040")
        emu.start()
        with connect(emu.port, check=False, import_image=False, timeout=60) as b:
            rep = deploy(b, progress=lambda m: say("deploy: " + m))
            res["deployed_files"] = rep["written"]
        with connect(emu.port, timeout=120) as b:
            say("starting board file %r with the split screen (the board builds it)" % BOARD)
            st = b.start(BOARD)
            res["firmware"] = st["firmware"]
            b.link.exec((DEVICE_SCRIPTS / "rp2_chip_bench.py").read_text(), timeout=60)
            mode, source, top, freq, hz, period_us, cc_addr, mul, mfreq = b.link.eval(
                "print(repr(_tpb_info()))")
            res.update({"mode": mode, "irq_source": source, "pwm_top": top,
                        "carrier_set_hz": board["carrier"]["freq_hz"], "pwm_freq_hz": freq,
                        "refresh_hz": hz, "period_us": period_us, "machine_freq": mfreq})
            if mfreq != CPU_HZ:
                raise ChipBenchError("machine.freq() is %d, expected %d" % (mfreq, CPU_HZ))
            res["irq"] = _irq_cost(b, irq_reps, say)
            res["holds"] = _holds(b, board, holds, cc_addr, 16 * (pin & 1), say)
            res["soak"] = _soak(b, soak_s, period_us, say)
    finally:
        summary = emu.stop()
    res["emulator_summary"] = summary.strip()
    probes = parse_probes(summary)
    res["probe"] = probes.get(pin)
    if res["probe"] and res["probe"]["carrier_hz"]:
        p = res["probe"]
        p["set_error_pct"] = 100.0 * (p["carrier_hz"] / res["carrier_set_hz"] - 1.0)
        p["pwm_error_pct"] = 100.0 * (p["carrier_hz"] * (top + 1) / CPU_HZ - 1.0)
    res["wall_s"] = time.monotonic() - t_wall
    return res


def _irq_cost(b: Any, reps: int, say: Progress) -> dict[str, Any]:
    say("refresh cost: busy loop with and without the refresh interrupt, %d x" % reps)
    rows = b.link.eval("print(repr(_tpb_irq_cost(%d, %d, %d)))" % (IRQ_SPIN, reps, IRQ_GAP_MS),
                       timeout=600)
    per = []
    for on, off, n, pos in rows:
        if n <= 0:
            raise ChipBenchError("no refresh ran during the busy loop (%r)" % (rows,))
        per.append({"on_us": on, "off_us": off, "refreshes": n, "position": pos,
                    "us": (on - off) / n, "cycles": (on - off) * (CPU_HZ / 1e6) / n})
    us = [r["us"] for r in per]
    # by the split screen's half under the finger at the window's end (the
    # finger moves ~2 % of the display per window): reference map | texel plan
    half = b.link.eval("print(repr(_tpb_app._rt.board['display']['positions'] // 2))")
    by: dict[str, list[float]] = {}
    for r in per:
        r["region"] = "reference map" if r["position"] < half else "texel plan"
        by.setdefault(r["region"], []).append(r["us"])
    out = {"spin": IRQ_SPIN, "reps": per, "median_us": statistics.median(us),
           "by_region_median_us": {k: statistics.median(v) for k, v in sorted(by.items())},
           "max_us": max(us), "min_us": min(us),
           "median_cycles": statistics.median(r["cycles"] for r in per),
           "exception_cycles_not_counted": EXCEPTION_CYCLES}
    out["median_us_with_exception"] = out["median_us"] + EXCEPTION_CYCLES / (CPU_HZ / 1e6)
    say("refresh cost incl. IRQ entry/exit: median %.2f us (%.0f cycles), max %.2f us"
        % (out["median_us"], out["median_cycles"], out["max_us"]))
    return out


def _holds(b: Any, board: dict[str, Any], holds: list[int], cc_addr: int, cc_shift: int,
           say: Progress) -> dict[str, Any]:
    """The finger held still: what plays against the scene's map."""
    from texel.app import DEFAULT_SCENE
    from texel.runtime import scene as scene_mod
    from texel.runtime.duty import DutyLaw, duty_fraction
    display, sensor = board["display"], board["sensor"]
    cap = board["carrier"]["duty_cap"]
    say("amplitude at the finger: %d holds (the board waits for the next hold cycle)"
        % len(holds))
    us = lambda s: int(round(s * 1e6))      # noqa: E731
    rows = b.link.eval("print(repr(_tpb_holds(%d, %d, %d, %d, %d, %d, %d)))" % (
        us(CYCLE_S), us(SWEEP_S), us(HOLD_S), len(holds), us(SAMPLE_AT_S), cc_addr, cc_shift),
        timeout=600)
    # the map: the same scene built here (texel's integer engine: the board's arithmetic)
    canonical = scene_mod.validate(DEFAULT_SCENE, display)
    sc = scene_mod.build(canonical, display, idle_default=board["carrier"].get(
        "idle_amplitude", 0))
    top = b.link.eval("print(repr(_tpb_app._rt.hw.top))")
    law = DutyLaw(top, cap)
    out = []
    for c, (t, pos, amp, duty, cc) in zip(holds, rows):
        ideal = ideal_position(c, sensor, display["positions"])
        want_pos = int(round(ideal))
        map_amp = sc.amp(want_pos)
        want_duty = duty_fraction(map_amp / 65535.0, cap) * (top + 1)
        out.append({"adc12": c, "t_us": t, "ideal_position": ideal, "position": pos,
                    "position_error": pos - want_pos, "map_amplitude": map_amp,
                    "amplitude": amp, "amplitude_error": amp - map_amp,
                    "law_duty": law.duty(map_amp), "duty": duty, "cc": cc,
                    "ideal_duty": want_duty, "cc_error_steps": cc - want_duty,
                    "region": "reference" if want_pos < display["positions"] // 2 else "texel"})
    worst = max(abs(r["cc_error_steps"]) for r in out)
    say("amplitude: worst |CC - map's duty| %.2f PWM steps over %d holds" % (worst, len(out)))
    return {"rows": out, "worst_cc_error_steps": worst,
            "positions_exact": all(r["position_error"] == 0 for r in out),
            "amplitudes_exact": all(r["amplitude_error"] == 0 for r in out),
            "cc_equals_duty": all(r["cc"] == r["duty"] for r in out),
            "cc_equals_law": all(r["cc"] == r["law_duty"] for r in out),
            "hold_s": HOLD_S, "sample_at_s": SAMPLE_AT_S, "cycle_s": CYCLE_S}


def _soak(b: Any, soak_s: float, period_us: int, say: Progress) -> dict[str, Any]:
    """Pushes from the host while the finger sweeps, for >= soak_s emulated s."""
    say("soak: pushing texel textures for %.1f s of emulated time" % soak_s)
    snap = lambda reset=False: b.link.eval(      # noqa: E731
        "print(repr(_tpb_snap(%s)))" % ("True" if reset else "False"))
    s0 = snap(True)
    t_end_wall = time.monotonic() + 120.0 + 30.0 * soak_s     # a wall-clock guard
    pushes, build_us, mem = 0, [], []
    now = s0
    while now[0] - s0[0] < soak_s * 1e6:
        if time.monotonic() > t_end_wall:
            raise ChipBenchError("soak: %.1f s of emulated time did not pass in %.0f s of wall "
                                 "time" % (soak_s, 120.0 + 30.0 * soak_s))
        params = {"pitch_db": round(-5.0 + 20.0 * (pushes % 97) / 97, 3),
                  "irregularity_db": -12.9, "seed": pushes}
        st = b.push_texel(params)
        pushes += 1
        if st.get("last_push"):
            build_us.append(st["last_push"]["build_us"] + st["last_push"]["swap_us"])
        now = snap()
        mem.append(now[5])
    dt = now[0] - s0[0]
    n = (now[1] - s0[1]) & 0x3FFFFFFF
    due = dt / period_us
    out = {"emulated_s": dt / 1e6, "refreshes": n, "due": due, "rate_hz": n * 1e6 / dt,
           "missed": due - n, "overruns": now[2] - s0[2], "worst_us": now[3],
           "faults": now[4] - s0[4], "pushes": pushes,
           "push_board_ms_median": statistics.median(build_us) / 1e3 if build_us else None,
           "mem_free_min": min(mem) if mem else None}
    say("soak: %d refreshes in %.3f s (%.1f Hz), %d overruns, worst %d us, %d pushes"
        % (n, dt / 1e6, out["rate_hz"], out["overruns"], out["worst_us"], pushes))
    return out


def opcount_check(chip: dict[str, Any], estimates: list[Any]) -> dict[str, Any] | None:
    """How far the op-count ESTIMATE of the mode the chip ran was off from the
    measured cost (incl. IRQ entry and exit)."""
    est = next((e for e in estimates if e.path == chip.get("mode")), None)
    if est is None or "irq" not in chip:
        return None
    meas = chip["irq"]["median_us"]
    return {"path": est.path, "estimate_us": est.est_us, "measured_us": meas,
            "ratio": est.est_us / meas if meas else None,
            "error_pct": 100.0 * (est.est_us / meas - 1.0) if meas else None}


def table_lines(chip: dict[str, Any], check: dict[str, Any] | None, goal_us: float,
                budget_us: int) -> list[str]:
    """The chip's figures as lines for bench-refresh's table."""
    out = ["EMULATED CHIP: %s (rp2040js, %s), board file %r, refresh %s via %s"
           % (chip["chip"].upper(), chip.get("firmware", "?"), chip["board"],
              chip.get("mode", "?"), chip.get("irq_source", "?"))]
    irq = chip.get("irq")
    if irq:
        out.append("  refresh cost incl. IRQ entry/exit: median %.2f us = %.0f cycles (min %.2f, "
                   "max %.2f over %d windows; goal <= %g us: %s); with the %d cycles of "
                   "exception entry/exit a Cortex-M0+ adds and rp2040js does not count: %.2f us"
                   % (irq["median_us"], irq["median_cycles"], irq["min_us"], irq["max_us"],
                      len(irq["reps"]), goal_us, "yes" if irq["median_us"] <= goal_us else "no",
                      irq["exception_cycles_not_counted"], irq["median_us_with_exception"]))
        out.append("    by the region under the finger (split screen): " + "; ".join(
            "%s %.2f us" % kv for kv in irq.get("by_region_median_us", {}).items()))
        out.append("    method: a viper busy loop of %s iterations timed with the chip's clock "
                   "with the refresh interrupt running and stopped; (on - off) / refreshes "
                   "in the window. Per window (position, us): %s"
                   % (format(irq["spin"], ","), ", ".join(
                       "%d: %.2f" % (r["position"], r["us"]) for r in irq["reps"])))
    soak = chip.get("soak")
    if soak:
        out.append("  rate over %.2f s of emulated time, %d host pushes, finger sweeping: %s "
                   "refreshes of %.1f due = %.2f Hz; %d overruns (body > %d us), worst body "
                   "%d us, %d faults; board push (build + swap) median %s ms"
                   % (soak["emulated_s"], soak["pushes"], format(soak["refreshes"], ","),
                      soak["due"], soak["rate_hz"], soak["overruns"], budget_us,
                      soak["worst_us"], soak["faults"],
                      "-" if soak["push_board_ms_median"] is None
                      else "%.0f" % soak["push_board_ms_median"]))
    p = chip.get("probe")
    if p:
        out.append("  carrier on GPIO%d (emulator's probe): %s Hz (%d-cycle period, %.1f %% of "
                   "periods), %+.3f %% from the set %s Hz (%+.4f %% from clk/(TOP+1)); duty "
                   "mean %.3f, min %s, max %s over the session"
                   % (chip["probe_gpio"], p["carrier_hz"], p["period_cycles"],
                      p["period_share_pct"], p["set_error_pct"],
                      format(chip["carrier_set_hz"], ","), p["pwm_error_pct"], p["duty_mean"],
                      p["duty_min"], p["duty_max"]))
    elif "emulator_summary" in chip:
        out.append("  carrier: the probe reported nothing (%s)" % chip["emulator_summary"][:200])
    h = chip.get("holds")
    if h:
        out.append("  amplitude at the finger, %d holds: worst |CC - ideal duty of the map| = "
                   "%.2f PWM steps (goal <= 1); positions exact: %s, amplitudes = map: %s, "
                   "CC = duty law: %s" % (len(h["rows"]), h["worst_cc_error_steps"],
                                          h["positions_exact"], h["amplitudes_exact"],
                                          h["cc_equals_law"]))
        out.append("    (adc12 -> position, map amp, CC, ideal duty): " + ", ".join(
            "%d->%d %d %d %.2f" % (r["adc12"], r["position"], r["map_amplitude"], r["cc"],
                                   r["ideal_duty"]) for r in h["rows"]))
    if check:
        out.append("  op-count ESTIMATE for %s: %.1f us vs %.2f us measured: off by %+.0f %%"
                   % (check["path"], check["estimate_us"], check["measured_us"],
                      check["error_pct"]))
    out.append("  wall time %.0f s" % chip.get("wall_s", 0.0))
    return out
