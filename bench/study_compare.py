"""Benchmark for texelpad lab: how many answers a simulated participant needs
to bring the guided exploration (the pursuit vector, seed 000; ../shared/
SPEC.md §5) and the preference-driven search (CMA-ES, seed 003; SPEC §7)
within 1 dB of each of the nine reference textures, side by side - per
answer, and at equal numbers of textures felt (issue 20).

    .venv/bin/python -m bench.study_compare [--seeds N] [--noise DB [DB ...]]
        [--max-answers N] [--picks N] [--feel felt|plane]
        [--update rank_one|positive|active] [--json PATH] [--figure PATH]

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

Equal effort, in textures felt (the reference, felt in both, not counted): a
comparison feels 2 (A and B), a pick 3 candidates. Two budgets: --picks
search picks (default 5: seed 003's participants stopped after 3.8 - 5.4
selection iterations per texture, mean 4.76 - its Table I, "around five") =
15 textures, and the pursuit's whole 20 comparisons = 40. Each method is
read after the most answers whose textures fit the budget: at 15 the
search after 5 picks, the pursuit after 7 comparisons (14 textures; the
8th's second texture is not felt yet); at 40 the pursuit after its 20, the
search after 13 picks (39; 14 would be 42). A partial pursuit trial is
counted two ways: "centre" - the centre after the last finished trial (the
protocol's own estimate; at 7 comparisons, after trial 1) - and "so far" -
that centre moved by the pursuit vector of the current trial's answers given
(the unanswered counted as "unsure", as pursuit.py's step would move it).

Seeds: run k uses participant seed k and protocol seed 1000 + k (the
pursuit's question order and A/B sides, the search's `cma` seed and
ranking), the same for every reference and noise level; each method gets a
fresh participant, so both see the same noise stream.

Prints two tables per noise level (per answer; at equal effort: medians and
quartiles over the seeds), writes every run's distance curves with --json and
a figure of the median curves with --figure (per reference: against textures
felt up to the 40, and against answers). Never fails on time.
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

from texelpad.search.preference import UPDATES, PreferenceSearch
from texelpad.study import references as R
from texelpad.analysis.perception import JND_DB
from texelpad.study.participant import FEELS, SimulatedParticipant
from texelpad.study.pursuit import DIRECTIONS, Pursuit
from texelpad.study.space import PITCH_DB_PER_U, Point, irregularity_db, pitch_db

DEFAULT_UPDATE = PreferenceSearch.cma_update     # the search's own default (seed 003's)

WITHIN_DB = 1.0
PROTOCOL_SEED_OFFSET = 1000     # protocol seed = participant seed + this (independent streams)
DEFAULT_SEEDS = 20
DEFAULT_NOISE_DB = (0.0, 1.0)
DEFAULT_MAX_ANSWERS = 60        # search answers (picks); the pursuit always asks its 20
METHODS = ("pursuit", "search")
# textures felt per answer, the reference not counted (felt in both): a comparison feels A and
# B, a pick the iteration's 3 candidates (texelpad.search.preference.POPSIZE)
TEXTURES_PER_ANSWER = {"pursuit": 2, "search": 3}
# seed 003, Table I: 3.8 - 5.4 selection iterations per texture (mean 4.76), "around five"
DEFAULT_PICKS = 5

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


def _so_far(pv: Pursuit) -> Point:
    """The centre moved by the current trial's pursuit vector of the answers
    given so far (the unanswered count 0, as "unsure"): where pursuit.py's
    step would put it if the trial ended now, clamped as it clamps."""
    pu, pvv = pv.pursuit_vector()
    c = Point(pv.centre.u + pu * pv.config.step, pv.centre.v + pvv * pv.config.step)
    return c.clamped() if pv.config.clamp_centre else c


def run_pursuit_curves(target: Point, noise_db: float, seed: int,
                       feel: str = "felt") -> tuple[list[float], list[float]]:
    """The distance (dB) after 0, 1, ..., 20 answers of the pursuit's centre
    (after the last finished trial) and of its estimate "so far" (_so_far;
    the centre itself after a trial's last answer)."""
    who = _participant(target, noise_db, seed, feel)
    pv = Pursuit(seed=seed + PROTOCOL_SEED_OFFSET)
    curve = [_distance(who, pv.centre.u, pv.centre.v)]
    partial = [curve[0]]
    while not pv.done:
        q = pv.next_comparison()
        assert q is not None                    # not done: a comparison is due
        trial = pv.trial
        pv.answer(who.compare(q.a, q.b))
        curve.append(_distance(who, pv.centre.u, pv.centre.v))
        if pv.trial != trial:                   # this answer finished the trial: the centre moved
            partial.append(curve[-1])
        else:
            c = _so_far(pv)
            partial.append(_distance(who, c.u, c.v))
    return curve, partial


def run_pursuit(target: Point, noise_db: float, seed: int, feel: str = "felt") -> list[float]:
    """The distance (dB) of the pursuit's centre after 0, 1, ..., 20 answers."""
    return run_pursuit_curves(target, noise_db, seed, feel)[0]


def run_search(target: Point, noise_db: float, seed: int, max_answers: int,
               feel: str = "felt", update: str = DEFAULT_UPDATE) -> list[float]:
    """The distance (dB) of the search's mean after 0, 1, ..., max_answers picks
    (update: the search's cma_update, texelpad.search.preference)."""
    who = _participant(target, noise_db, seed, feel)
    s = PreferenceSearch(seed=seed + PROTOCOL_SEED_OFFSET, x0=(0.5, 0.5), cma_update=update)
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


def quantile(values: Sequence[float], q: float) -> float:
    """The q-quantile, linear between order statistics (the figure's rule)."""
    s = sorted(values)
    x = q * (len(s) - 1)
    lo = int(math.floor(x))
    hi = min(lo + 1, len(s) - 1)
    return s[lo] + (s[hi] - s[lo]) * (x - lo)


def budgets(picks: int, pursuit_answers: int) -> list[int]:
    """The equal-effort budgets in textures felt: `picks` search picks, and
    the pursuit's whole exploration (module docstring)."""
    return sorted({picks * TEXTURES_PER_ANSWER["search"],
                   pursuit_answers * TEXTURES_PER_ANSWER["pursuit"]})


def answers_within(method: str, textures: int) -> int:
    """The most answers of `method` whose textures felt fit in `textures`."""
    return textures // TEXTURES_PER_ANSWER[method]


def _spread(values: list[float]) -> dict:
    return {"median": quantile(values, 0.5), "q1": quantile(values, 0.25),
            "q3": quantile(values, 0.75), "within": sum(d <= WITHIN_DB for d in values) / len(values)}


def effort(runs: list[dict], method: str, textures: int) -> dict:
    """One method's distances (dB) at a budget of textures felt: median,
    quartiles, fraction within 1 dB; the pursuit's "so far" too. Answers
    and textures are those actually read; None when the runs are shorter."""
    k = answers_within(method, textures)
    out: dict[str, Any] = {"answers": k, "textures": k * TEXTURES_PER_ANSWER[method]}
    if any(len(r["curve_db"]) <= k for r in runs):
        out.update(dict.fromkeys(("median", "q1", "q3", "within")))
        return out
    out.update(_spread([r["curve_db"][k] for r in runs]))
    if method == "pursuit":
        out["so_far"] = _spread([r["partial_db"][k] for r in runs])
    return out


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


def _one_run(method: str, t: Point, noise: float, seed: int, max_answers: int,
             feel: str, update: str = DEFAULT_UPDATE) -> dict[str, Any]:
    if method == "pursuit":
        curve, partial = run_pursuit_curves(t, noise, seed, feel)
        extra = {"partial_db": partial}
    else:
        curve, extra = run_search(t, noise, seed, max_answers, feel, update), {}
    return {"method": method, "answers": len(curve) - 1,
            "textures_per_answer": TEXTURES_PER_ANSWER[method],
            "answers_to_1db": first_within(curve), "final_db": curve[-1], "curve_db": curve,
            **extra}


def run(references: Sequence[str] = R.REFERENCES, seeds: int = DEFAULT_SEEDS,
        noise_db: Sequence[float] = DEFAULT_NOISE_DB, max_answers: int = DEFAULT_MAX_ANSWERS,
        progress: Progress | None = None, feel: str = "felt", picks: int = DEFAULT_PICKS,
        update: str = DEFAULT_UPDATE) -> dict:
    """Every (reference, noise, seed, method) run and the summaries."""
    if update not in UPDATES:
        raise ValueError("update: expected one of %s, got %r" % (", ".join(UPDATES), update))
    if feel not in FEELS:
        raise ValueError("feel: expected one of %s, got %r" % (", ".join(FEELS), feel))
    if seeds < 1 or max_answers < 1:
        raise ValueError("seeds and max_answers: expected >= 1, got %r, %r" % (seeds, max_answers))
    if not 1 <= picks <= max_answers:
        raise ValueError("picks: expected 1 .. max_answers (%d), got %r" % (max_answers, picks))
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
                    results.append({"reference": name, "noise_db": noise, "seed": seed,
                                    **_one_run(method, t, noise, seed, max_answers, feel,
                                               update)})
        if progress:
            progress("study_compare: %d/%d %s done (%.1f s)"
                     % (i + 1, len(references), name, time.perf_counter() - t0))
    pursuit_answers = next(r["answers"] for r in results if r["method"] == "pursuit")
    textures = budgets(picks, pursuit_answers)
    summary = []
    for noise in noise_db:
        for name in list(references) + ["all"]:
            row: dict[str, Any] = {"noise_db": noise, "reference": name,
                                   "effort": [{"textures": b} for b in textures]}
            for method in METHODS:
                group = [r for r in results if r["noise_db"] == noise and r["method"] == method
                         and name in ("all", r["reference"])]
                row[method] = summarise(group, pursuit_answers)
                for e in row["effort"]:
                    e[method] = effort(group, method, e["textures"])
            summary.append(row)
    return {"config": {"references": list(references), "seeds": seeds,
                       "noise_db": list(noise_db), "max_answers": max_answers,
                       "pursuit_answers": pursuit_answers, "within_db": WITHIN_DB,
                       "picks": picks, "budgets_textures": textures,
                       "textures_per_answer": TEXTURES_PER_ANSWER,
                       "protocol_seed_offset": PROTOCOL_SEED_OFFSET,
                       "weighting": R.WEIGHTING, "x0": [0.5, 0.5], "feel": feel,
                       "cma_update": update,
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


def _effort_columns(res: dict) -> list[tuple[int, str, str, int]]:
    """(budget, method, "" or "so_far", answers) per column of the equal-
    effort table: per budget the search, the pursuit's centre and - when the
    budget ends inside a trial - its estimate so far."""
    cfg = res["config"]
    cols = []
    for b in cfg["budgets_textures"]:
        k = answers_within("pursuit", b)
        order = ("search", "pursuit") if b < cfg["pursuit_answers"] * 2 else ("pursuit", "search")
        for method in order:
            cols.append((b, method, "", answers_within(method, b)))
            if method == "pursuit" and k % len(DIRECTIONS) and k < cfg["pursuit_answers"]:
                cols.append((b, method, "so_far", k))
    return cols


def _cell(e: dict) -> str:
    if e.get("median") is None:
        return "-"
    return "%.1f [%.1f-%.1f]" % (e["median"], e["q1"], e["q3"])


def format_effort(res: dict) -> str:
    """The equal-effort tables: distances (dB) at each budget of textures felt."""
    cfg = res["config"]
    cols = _effort_columns(res)
    w = 18
    lines = ["equal effort: distance (dB) of the estimate to the target after a number of "
             "textures felt (2 per comparison, A and B; 3 per pick; the reference not counted)",
             "  median [quartiles] over %d seeds; each method read after the most answers that "
             "fit the budget" % cfg["seeds"],
             "  pursuit: its centre after the last finished trial; so far: that centre moved by "
             "the current trial's pursuit vector of the answers given (the rest as unsure)"]
    head1 = "%-9s" % "budget"
    head2 = "%-9s" % "reference"
    for b, method, part, k in cols:
        head1 += " | %-*s" % (w, "%d textures felt" % b)
        what = ("search %d picks" % k if method == "search"
                else "pursuit %d: %s" % (k, "so far" if part else "centre"))
        head2 += " | %-*s" % (w, what)
    head3 = "%-9s" % "" + "".join(" | %-*s" % (w, "(%d textures)" % (k * TEXTURES_PER_ANSWER[m]))
                                  for _, m, _, k in cols)
    for noise in cfg["noise_db"]:
        label = "participant noise SD %g dB%s" % (noise, " (noiseless)" if noise == 0 else "")
        lines += ["", label] + [h.rstrip() for h in (head1, head2, head3)] + ["-" * len(head2)]
        for row in res["summary"]:
            if row["noise_db"] != noise:
                continue
            effort_by = {e["textures"]: e for e in row["effort"]}
            cells = []
            for b, method, part, _ in cols:
                e = effort_by[b][method]
                cells.append(_cell(e[part] if part else e))
            if row["reference"] == "all":
                lines.append("-" * len(head2))
            lines.append(("%-9s" % row["reference"]
                          + "".join(" | %-*s" % (w, c) for c in cells)).rstrip())
            if row["reference"] == "all":
                within = []
                for b, method, part, _ in cols:
                    e = effort_by[b][method]
                    e = e[part] if part else e
                    within.append("-" if e.get("within") is None else "%.2f" % e["within"])
                lines.append(("%-9s" % "within 1" + "".join(" | %-*s" % (w, c)
                                                             for c in within)).rstrip())
    return "\n".join(lines)


def _quantiles(curves: list[list[float]], q: float) -> list[float]:
    return [quantile(c, q) for c in zip(*curves)]


STYLES = ["-", "--", ":", "-."]
COLOURS = {"pursuit": "C0", "search": "C1"}


def _draw(ax, res: dict, name: str, per_texture: bool) -> None:
    """One reference's median curves (quartiles shaded), both methods, every
    noise level; x in textures felt (per_texture) or in answers."""
    cfg = res["config"]
    for j, noise in enumerate(cfg["noise_db"]):
        for method in METHODS:
            curves = [r["curve_db"] for r in res["results"] if r["reference"] == name
                      and r["noise_db"] == noise and r["method"] == method]
            scale = TEXTURES_PER_ANSWER[method] if per_texture else 1
            x = [k * scale for k in range(len(curves[0]))]
            # the pursuit's centre moves after every 4th answer and holds between: steps
            step = "post" if method == "pursuit" else None
            ax.plot(x, _quantiles(curves, 0.5), STYLES[j % len(STYLES)], color=COLOURS[method],
                    lw=1.4, drawstyle="steps-post" if step else "default",
                    label="%s, noise %g dB" % (method, noise))
            ax.fill_between(x, _quantiles(curves, 0.25), _quantiles(curves, 0.75),
                            color=COLOURS[method], alpha=0.10, lw=0, step=step)
    ax.axhline(cfg["within_db"], color="0.3", lw=0.8)
    if per_texture:
        for b in cfg["budgets_textures"]:
            ax.axvline(b, color="0.5", lw=0.8, ls=":")
        ax.set_xlim(0, max(cfg["budgets_textures"]) + 5)
    else:
        ax.axvline(cfg["pursuit_answers"], color="0.7", lw=0.8, ls=":")
        ax.set_xlim(0, max(cfg["max_answers"], cfg["pursuit_answers"]))


def figure(res: dict, path: str) -> None:
    """Per reference two panels: the median distance against textures felt
    (up to the pursuit's 40; dotted: the budgets) and against answers (all of
    them; dotted: the pursuit's 20th). Quartiles shaded, both methods, every
    noise level (matplotlib Agg canvas; pyplot's global state is never
    touched, as texelpad.analysis.figures)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    cfg = res["config"]
    names = cfg["references"]
    ncol = min(3, len(names))
    nrow = (len(names) + ncol - 1) // ncol
    fig = Figure(figsize=(6.4 * ncol, 2.9 * nrow + 0.7), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrow, 2 * ncol, squeeze=False, sharey=True,
                        gridspec_kw={"width_ratios": [1.0, 1.0] * ncol})
    top = max(r["curve_db"][0] for r in res["results"])
    for k, name in enumerate(names):
        t = res["targets"][name]
        for half, per_texture in enumerate((True, False)):
            ax = axes[k // ncol][2 * (k % ncol) + half]
            _draw(ax, res, name, per_texture)
            ax.set_ylim(0, top * 1.05)
            ax.set_title("%s (%.1f dB, %.1f dB), %s" % (
                name, t["pitch_db"], t["irregularity_db"],
                "by textures felt" if per_texture else "by answers"), fontsize=9)
            if k // ncol == nrow - 1 or k + ncol >= len(names):
                ax.set_xlabel("textures felt" if per_texture else "answers")
        if k % ncol == 0:
            axes[k // ncol][0].set_ylabel("distance to target (dB)")
    for k in range(len(names), nrow * ncol):
        for half in (0, 1):
            axes[k // ncol][2 * (k % ncol) + half].set_visible(False)
    axes[0][0].legend(fontsize=7, loc="upper right")
    fig.suptitle("pursuit (a comparison: 1 answer, 2 textures) vs search (a pick of 3: 1 answer, "
                 "3 textures): median and quartiles over %d seeds; line: %g dB; dotted: %s "
                 "textures felt, the pursuit's %d answers"
                 % (cfg["seeds"], cfg["within_db"],
                    " and ".join(str(b) for b in cfg["budgets_textures"]),
                    cfg["pursuit_answers"]), fontsize=10)
    fig.savefig(path, dpi=80)


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
    p.add_argument("--picks", type=int, default=DEFAULT_PICKS,
                   help="the search's picks at the smaller equal-effort budget (3 textures "
                        "each; default %(default)s: seed 003's participants stopped after "
                        "about five)")
    p.add_argument("--feel", choices=FEELS, default="felt",
                   help="the participant's distance: felt (the felt plane, the default) or "
                        "plane (the unit square's Euclidean oracle)")
    p.add_argument("--update", choices=UPDATES, default=DEFAULT_UPDATE,
                   help="the search's covariance update (texelpad.search.preference "
                        "cma_update; default %(default)s, seed 003's)")
    p.add_argument("--json", metavar="PATH")
    p.add_argument("--figure", metavar="PATH")
    a = p.parse_args(argv)
    if a.seeds < 1 or a.max_answers < 1:
        p.error("--seeds and --max-answers: expected >= 1")
    if not 1 <= a.picks <= a.max_answers:
        p.error("--picks: expected 1 .. --max-answers (%d), got %d" % (a.max_answers, a.picks))
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
              feel=a.feel, picks=a.picks, update=a.update)
    print(format_table(res))
    print()
    print(format_effort(res))
    print("\n%d runs in %.1f s" % (len(res["results"]), res["seconds"]))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    if a.figure:
        figure(res, a.figure)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
