"""Benchmark for texelpad lab: how many answers a simulated participant needs
to bring the guided exploration (the pursuit vector, seed 000; ../shared/
SPEC.md §5) and the preference-driven search (CMA-ES, seed 003; SPEC §7)
within 1 dB of each of the nine reference textures, side by side.

    .venv/bin/python -m bench.study_compare [--seeds N] [--noise DB [DB ...]]
        [--max-answers N] [--json PATH] [--figure PATH]

The model (docs/lab-benchmark.md):
- targets: texelpad.study.references.target_point - each reference's point
  on the pitch - irregularity plane by a spectral model (power-weighted
  geometric mean frequency and SD of log10 f; that module's docstring);
- the participant: texelpad.study.participant.SimulatedParticipant aiming
  at that point, noise SD given in dB of pitch (its own unit is the
  normalised space's: 1 dB = 1/40 = 0.025, texelpad.study.space). --feel
  felt (the default): it feels the distance on the felt plane
  (texelpad.analysis.perception: felt pitch and noisiness) and answers
  "unsure" within one difference threshold (1 dB); --feel plane: the
  Euclidean oracle of the unit square, never "unsure";
- an answer: the pursuit - one pairwise comparison (20 in all, 5 trials of
  4; the centre moves after every fourth); the search - one pick of 3
  candidates (one CMA-ES iteration), up to --max-answers. Both start at the
  centre (0.5, 0.5);
- the estimate: the pursuit's centre, the search's mean; its distance to
  the target is the participant's own: on the felt plane (felt), or
  Euclidean in (pitch dB, irregularity dB) - 40 dB per unit of u, 30 dB per
  unit of v - (plane); "within 1 dB" is distance <= 1 dB. Counted:
  the answers until the estimate is first within 1 dB (0 = at the start),
  whether it is within 1 dB after the last answer, the final distance.

Seeds: run k uses participant seed k and protocol seed 1000 + k (the
pursuit's question order and A/B sides, the search's `cma` seed and
ranking), the same for every reference and noise level; each method gets a
fresh participant, so both see the same noise stream.

Prints one table per noise level, writes every run's distance curve with
--json and a figure of the median curves with --figure. Never fails on time.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any, Callable, Sequence

from texelpad.search.preference import PreferenceSearch
from texelpad.study import references as R
from texelpad.analysis.perception import JND_DB
from texelpad.study.participant import FEELS, SimulatedParticipant
from texelpad.study.pursuit import Pursuit
from texelpad.study.space import PITCH_DB_PER_U, Point, irregularity_db, pitch_db

WITHIN_DB = 1.0
PROTOCOL_SEED_OFFSET = 1000     # protocol seed = participant seed + this (independent streams)
DEFAULT_SEEDS = 20
DEFAULT_NOISE_DB = (0.0, 1.0)
DEFAULT_MAX_ANSWERS = 60        # search answers (picks); the pursuit always asks its 20
METHODS = ("pursuit", "search")

Progress = Callable[[str], None]


def distance_db(u: float, v: float, target: Point) -> float:
    """Euclidean distance in the (pitch dB, irregularity dB) plane."""
    return math.hypot(pitch_db(u) - pitch_db(target.u),
                      irregularity_db(v) - irregularity_db(target.v))


def _participant(target: Point, noise_db: float, seed: int, feel: str) -> SimulatedParticipant:
    # SimulatedParticipant's noise is in normalised units (participant.py: 0.025 = 1 dB of pitch)
    return SimulatedParticipant(target, noise=noise_db / PITCH_DB_PER_U, seed=seed, feel=feel,
                                unsure_below=0.0 if feel == "plane" else None)


def _distance(who: SimulatedParticipant, u: float, v: float) -> float:
    """The estimate's distance to the target in dB, by the participant's own
    measure (module docstring)."""
    if who.feel == "plane":
        return distance_db(u, v, who.target)
    return who.distance(Point(u, v)) * PITCH_DB_PER_U


def run_pursuit(target: Point, noise_db: float, seed: int, feel: str = "felt") -> list[float]:
    """The distance (dB) of the pursuit's centre after 0, 1, ..., 20 answers."""
    who = _participant(target, noise_db, seed, feel)
    pv = Pursuit(seed=seed + PROTOCOL_SEED_OFFSET)
    curve = [_distance(who, pv.centre.u, pv.centre.v)]
    while not pv.done:
        q = pv.next_comparison()
        assert q is not None                    # not done: a comparison is due
        pv.answer(who.compare(q.a, q.b))
        curve.append(_distance(who, pv.centre.u, pv.centre.v))
    return curve


def run_search(target: Point, noise_db: float, seed: int, max_answers: int,
               feel: str = "felt") -> list[float]:
    """The distance (dB) of the search's mean after 0, 1, ..., max_answers picks."""
    who = _participant(target, noise_db, seed, feel)
    s = PreferenceSearch(seed=seed + PROTOCOL_SEED_OFFSET, x0=(0.5, 0.5))
    u, v = s.mean
    curve = [_distance(who, u, v)]
    for _ in range(max_answers):
        s.choose(who.pick(s.ask()))
        u, v = s.mean[:2]
        curve.append(_distance(who, u, v))
    return curve


def first_within(curve: Sequence[float], within: float = WITHIN_DB) -> int | None:
    """Answers until the curve is first <= within (None: never)."""
    for k, d in enumerate(curve):
        if d <= within:
            return k
    return None


def _median_answers(firsts: list[int | None]) -> float | None:
    """The median answers to 1 dB over runs, a run that never got there
    counting as infinitely many; None when that median is not finite."""
    m = statistics.median([math.inf if a is None else a for a in firsts])
    return None if math.isinf(m) else float(m)


def summarise(runs: list[dict], at: int) -> dict:
    """Figures of one group of runs (one method): median answers to 1 dB,
    the fraction that got there, the median distance after `at` answers and
    after the last, the fraction within 1 dB after the last."""
    firsts = [r["answers_to_1db"] for r in runs]
    return {"runs": len(runs),
            "median_answers": _median_answers(firsts),
            "reached": sum(a is not None for a in firsts) / len(runs),
            "median_db_at_%d" % at: statistics.median(r["curve_db"][min(at, len(r["curve_db"]) - 1)]
                                                      for r in runs),
            "median_final_db": statistics.median(r["final_db"] for r in runs),
            "held": sum(r["final_db"] <= WITHIN_DB for r in runs) / len(runs)}


def run(references: Sequence[str] = R.REFERENCES, seeds: int = DEFAULT_SEEDS,
        noise_db: Sequence[float] = DEFAULT_NOISE_DB, max_answers: int = DEFAULT_MAX_ANSWERS,
        progress: Progress | None = None, feel: str = "felt") -> dict:
    """Every (reference, noise, seed, method) run and the summaries."""
    if feel not in FEELS:
        raise ValueError("feel: expected one of %s, got %r" % (", ".join(FEELS), feel))
    if seeds < 1 or max_answers < 1:
        raise ValueError("seeds and max_answers: expected >= 1, got %r, %r" % (seeds, max_answers))
    if any(not (n >= 0.0 and math.isfinite(n)) for n in noise_db):
        raise ValueError("noise_db: expected finite numbers >= 0, got %r" % (list(noise_db),))
    if not references:
        raise ValueError("references: expected at least one of %s" % ", ".join(R.REFERENCES))
    t0 = time.perf_counter()
    targets = {}
    results: list[dict[str, Any]] = []
    for i, name in enumerate(references):
        t = R.target_point(name)
        targets[name] = {"pitch_db": pitch_db(t.u), "irregularity_db": irregularity_db(t.v),
                         "u": t.u, "v": t.v, "family": R.FAMILIES[name]}
        for noise in noise_db:
            for seed in range(seeds):
                for method in METHODS:
                    curve = (run_pursuit(t, noise, seed, feel) if method == "pursuit"
                             else run_search(t, noise, seed, max_answers, feel))
                    results.append({"reference": name, "noise_db": noise, "seed": seed,
                                    "method": method, "answers": len(curve) - 1,
                                    "answers_to_1db": first_within(curve),
                                    "final_db": curve[-1], "curve_db": curve})
        if progress:
            progress("study_compare: %d/%d %s done (%.1f s)"
                     % (i + 1, len(references), name, time.perf_counter() - t0))
    pursuit_answers = next(r["answers"] for r in results if r["method"] == "pursuit")
    summary = []
    for noise in noise_db:
        for name in list(references) + ["all"]:
            row = {"noise_db": noise, "reference": name}
            for method in METHODS:
                group = [r for r in results if r["noise_db"] == noise and r["method"] == method
                         and name in ("all", r["reference"])]
                row[method] = summarise(group, pursuit_answers)
            summary.append(row)
    return {"config": {"references": list(references), "seeds": seeds,
                       "noise_db": list(noise_db), "max_answers": max_answers,
                       "pursuit_answers": pursuit_answers, "within_db": WITHIN_DB,
                       "protocol_seed_offset": PROTOCOL_SEED_OFFSET,
                       "weighting": R.WEIGHTING, "x0": [0.5, 0.5], "feel": feel,
                       "unsure_db": 0.0 if feel == "plane" else JND_DB},
            "targets": targets, "results": results, "summary": summary,
            "seconds": time.perf_counter() - t0}


def _answers(m: float | None, cap: int) -> str:
    if m is None:
        return ">%d" % cap
    return ("%.0f" % m) if m == int(m) else ("%.1f" % m)


def format_table(res: dict) -> str:
    cfg = res["config"]
    at = cfg["pursuit_answers"]
    key = "median_db_at_%d" % at
    lines = ["answers to bring the estimate within %g dB of the reference's point "
             "(pursuit centre / search mean; %d seeds per cell)" % (cfg["within_db"], cfg["seeds"]),
             "  to 1dB: median answers until first within (>N: the median run never got there)",
             "  got:    fraction of runs that got there;  @%d: median distance (dB) after %d "
             "answers" % (at, at),
             "  end:    median distance (dB) after the last answer;  held: fraction within at "
             "the end"]
    pblock = "%6s %5s %5s %5s"             # to 1dB, got, end, held
    sblock = "%6s %5s %5s %5s %5s"         # to 1dB, got, @20, end, held
    head = "%-9s %6s %6s | %-23s | %s" % ("reference", "pitch", "irreg",
                                        "pursuit (%d answers)" % at,
                                        "search (%d answers)" % cfg["max_answers"])
    sub = ("%-9s %6s %6s | " + pblock + " | " + sblock) % (
        "", "dB", "dB", "to 1dB", "got", "end", "held", "to 1dB", "got", "@%d" % at, "end", "held")
    for noise in cfg["noise_db"]:
        label = "participant noise SD %g dB%s" % (noise, " (noiseless)" if noise == 0 else "")
        lines += ["", label, head, sub, "-" * len(sub)]
        for row in res["summary"]:
            if row["noise_db"] != noise:
                continue
            name = row["reference"]
            p, s = row["pursuit"], row["search"]
            if name == "all":
                lines.append("-" * len(sub))
                tgt = ("%6s %6s" % ("", ""))
            else:
                t = res["targets"][name]
                tgt = "%6.1f %6.1f" % (t["pitch_db"], t["irregularity_db"])
            lines.append("%-9s %s | %6s %5.2f %5.1f %5.2f | %6s %5.2f %5.1f %5.1f %5.2f"
                         % (name, tgt, _answers(p["median_answers"], at), p["reached"],
                            p["median_final_db"], p["held"],
                            _answers(s["median_answers"], cfg["max_answers"]), s["reached"],
                            s[key], s["median_final_db"], s["held"]))
    return "\n".join(lines)


def _quantiles(curves: list[list[float]], q: float) -> list[float]:
    cols = list(zip(*curves))
    out = []
    for c in cols:
        s = sorted(c)
        x = q * (len(s) - 1)
        lo = int(math.floor(x))
        hi = min(lo + 1, len(s) - 1)
        out.append(s[lo] + (s[hi] - s[lo]) * (x - lo))
    return out


def figure(res: dict, path: str) -> None:
    """Per reference: the median distance against answers (quartiles
    shaded), both methods, every noise level (matplotlib Agg canvas; pyplot's
    global state is never touched, as texelpad.analysis.figures)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    cfg = res["config"]
    names = cfg["references"]
    ncol = min(3, len(names))
    nrow = (len(names) + ncol - 1) // ncol
    fig = Figure(figsize=(4.2 * ncol, 3.2 * nrow + 0.6), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrow, ncol, squeeze=False, sharex=True)
    styles = ["-", "--", ":", "-."]
    colours = {"pursuit": "C0", "search": "C1"}
    top = max(r["curve_db"][0] for r in res["results"])
    for k, name in enumerate(names):
        ax = axes[k // ncol][k % ncol]
        t = res["targets"][name]
        for j, noise in enumerate(cfg["noise_db"]):
            for method in METHODS:
                curves = [r["curve_db"] for r in res["results"] if r["reference"] == name
                          and r["noise_db"] == noise and r["method"] == method]
                x = list(range(len(curves[0])))
                # the pursuit's centre moves after every 4th answer and holds between: steps
                step = "post" if method == "pursuit" else None
                ax.plot(x, _quantiles(curves, 0.5), styles[j % len(styles)],
                        color=colours[method], lw=1.4,
                        drawstyle="steps-post" if step else "default",
                        label="%s, noise %g dB" % (method, noise))
                ax.fill_between(x, _quantiles(curves, 0.25), _quantiles(curves, 0.75),
                                color=colours[method], alpha=0.10, lw=0, step=step)
        ax.axhline(cfg["within_db"], color="0.3", lw=0.8)
        ax.axvline(cfg["pursuit_answers"], color="0.7", lw=0.8, ls=":")
        ax.set_ylim(0, top * 1.05)
        ax.set_title("%s (%.1f dB, %.1f dB)" % (name, t["pitch_db"], t["irregularity_db"]),
                     fontsize=10)
        if k % ncol == 0:
            ax.set_ylabel("distance to target (dB)")
        if k // ncol == nrow - 1:
            ax.set_xlabel("answers")
    for k in range(len(names), nrow * ncol):
        axes[k // ncol][k % ncol].set_visible(False)
    axes[0][0].legend(fontsize=7, loc="upper right")
    fig.suptitle("pursuit (1 comparison = 1 answer) vs search (1 pick of 3 = 1 answer): "
                 "median and quartiles over %d seeds; line: %g dB" % (cfg["seeds"],
                                                                      cfg["within_db"]))
    fig.savefig(path, dpi=90)


FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def _unwritable(path: str) -> str | None:
    """Why `path` cannot be written (None: it can), found before the run so a
    typo costs no benchmark; nothing is created to find out."""
    p = Path(path)
    if p.is_dir():
        return "it is a directory"
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        return "no such directory %s" % parent
    if not os.access(parent, os.W_OK) or (p.exists() and not os.access(p, os.W_OK)):
        return "permission denied"
    return None


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m bench.study_compare",
                                description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seeds", type=int, default=DEFAULT_SEEDS,
                   help="participant seeds 0 .. N-1 per reference and noise (default %(default)s)")
    p.add_argument("--noise", type=float, nargs="+", default=list(DEFAULT_NOISE_DB), metavar="DB",
                   help="participant noise SD in dB of pitch (default 0 1)")
    p.add_argument("--max-answers", type=int, default=DEFAULT_MAX_ANSWERS,
                   help="the search's answers (picks) per run (default %(default)s)")
    p.add_argument("--feel", choices=FEELS, default="felt",
                   help="the participant's distance: felt (the felt plane, the default) or "
                        "plane (the unit square's Euclidean oracle)")
    p.add_argument("--json", metavar="PATH")
    p.add_argument("--figure", metavar="PATH")
    a = p.parse_args(argv)
    if a.seeds < 1 or a.max_answers < 1:
        p.error("--seeds and --max-answers: expected >= 1")
    if any(not (n >= 0.0 and math.isfinite(n)) for n in a.noise):
        p.error("--noise: expected finite numbers >= 0")
    if a.figure and Path(a.figure).suffix.lower() not in FIGURE_SUFFIXES:
        p.error("--figure: unsupported file type %r (expected %s)"
                % (Path(a.figure).suffix, ", ".join(FIGURE_SUFFIXES)))
    for flag, path in (("--json", a.json), ("--figure", a.figure)):
        why = path and _unwritable(path)
        if why:
            print("study_compare: %s: cannot write %s: %s" % (flag, path, why), file=sys.stderr)
            return 1

    def progress(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    res = run(seeds=a.seeds, noise_db=a.noise, max_answers=a.max_answers, progress=progress,
              feel=a.feel)
    print(format_table(res))
    print("\n%d runs in %.1f s" % (len(res["results"]), res["seconds"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    if a.figure:
        figure(res, a.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
