"""`texelpad lab export`: session files -> tidy CSV (one row per answer) and one
summary figure per session (pursuit: the centre's path on the pitch -
irregularity plane; staircase: the track with its reversals and threshold;
search: the mean's path and step size). Reads the files only (never a board).

A session that cannot be read or replayed (a damaged line, an answer its
protocol refuses) is reported by name with the reason and left out; the
others are exported. A data folder that does not exist, or holds no session,
is an error (nothing is written): an empty CSV would look like a study
without answers.
"""
from __future__ import annotations

import csv
import json
import math
import os
from pathlib import Path
from typing import Any

from . import protocols
from .session import Session, SessionError, sessions
from .space import irregularity_db, pitch_db

COLUMNS = ("participant", "protocol", "session", "config_file", "seed", "n", "time",
           "trial", "answer", "reference", "played_pitch_db", "played_irregularity_db",
           "played_texel_samples", "played_quant_db", "option_played",
           "match_pitch_db", "match_irregularity_db", "confidence", "similarity",
           "quant_db", "match_of", "correct", "length_mm", "chosen")


def _texel(scene: dict[str, Any] | None) -> dict[str, Any]:
    """The texel texture of a recorded scene (the rendering: its last texel region)."""
    regs = (scene or {}).get("regions") or []
    for r in reversed(regs):
        if r.get("texture", {}).get("kind") == "texel":
            return r["texture"]
    return {}


def _reference(scene: dict[str, Any] | None) -> str:
    for r in (scene or {}).get("regions") or []:
        if r.get("texture", {}).get("kind") == "reference":
            return r["texture"].get("name", "")
    return ""


def rows(s: Session) -> list[dict[str, Any]]:
    """One tidy row per answer: who, what was asked, what played, what was
    answered (a column per kind of answer; empty where it does not apply)."""
    h = s.header
    proto = h["protocol"]
    state = protocols.start(proto, h["config"], h["seed"])     # what each answer answered
    out = []
    for k, rec in enumerate(s.answers()):
        tex = _texel(rec.get("scene"))
        a: Any = rec.get("answer")          # the protocol's own answer (checked by apply)
        q = rec.get("question") or {}
        row: dict[str, Any] = {c: "" for c in COLUMNS}
        row.update(participant=h["participant"], protocol=proto, session=s.path.stem,
                   config_file=h["config"].get("config_file", ""), seed=h["seed"], n=k,
                   time=rec.get("time"), trial=q.get("trial", q.get("iteration", "")),
                   answer=json.dumps(a, sort_keys=True),
                   reference=_reference(rec.get("scene")),
                   played_pitch_db=tex.get("pitch_db", ""),
                   played_irregularity_db=tex.get("irregularity_db", ""),
                   played_texel_samples=tex.get("texel_samples", ""),
                   played_quant_db=tex.get("quant_db", "") if tex else "",
                   option_played="" if rec.get("playing") is None else rec["playing"])
        if proto == "free":
            row.update(match_pitch_db=a["pitch_db"], match_irregularity_db=a["irregularity_db"],
                       confidence=a["confidence"], reference=state.reference, trial=state.trial)
        elif proto == "quant":
            ref, level = state.current
            row.update(similarity=a, quant_db=level, reference=ref, trial=state.trial,
                       match_of=state.current_match)
        elif proto == "staircase":
            row.update(correct=a, length_mm=state.length_mm, trial=len(state.track))
        elif proto == "search" and "choose" in a:
            row.update(chosen=a["choose"], trial=state.iteration)
        protocols.apply(proto, state, a)
        out.append(row)
    return out


def session_files(data: str | os.PathLike) -> list[Path]:
    """The session files under data; SessionError when data is no folder or
    holds none."""
    root = Path(data)
    if not root.is_dir():
        raise SessionError("%s: %s" % (root, "not a folder" if root.exists() else
                                       "no such folder"))
    found = sessions(root)
    if not found:
        raise SessionError("%s: no session files (PARTICIPANT/PROTOCOL-N.jsonl) in it" % root)
    return found


def _load(path: Path) -> tuple[Session, list[dict[str, Any]]]:
    """A session and its rows, or SessionError saying why it cannot be exported."""
    try:
        s = Session.open(path)
        return s, rows(s)
    except SessionError:
        raise
    except OSError as e:
        raise SessionError("%s: %s" % (path, e.strerror or e)) from None
    except (ValueError, KeyError, TypeError, IndexError, AttributeError) as e:
        raise SessionError("%s: does not replay (%s: %s)"
                           % (path, type(e).__name__, str(e)[:200])) from None


def write_csv(data: str | os.PathLike, out: str | os.PathLike,
              broken: list[tuple[Path, str]] | None = None) -> tuple[Path, int]:
    """Every session under data as one CSV (written beside, then renamed).
    A session that cannot be exported goes into `broken` as (path, reason)
    (without a list: SessionError)."""
    out = Path(out)
    files = session_files(data)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    n = 0
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for path in files:
            try:
                _, rs = _load(path)
            except SessionError as e:
                if broken is None:
                    raise
                broken.append((path, str(e)))
                continue
            for r in rs:
                w.writerow(r)
                n += 1
    os.replace(tmp, out)
    return out, n


def figure(s: Session, out: str | os.PathLike) -> Path:
    """The session's summary figure (PNG): one plot per protocol (_PLOTS)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    h = s.header
    state = protocols.replay(s)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    title = "%s, %s (%s): %d answers" % (h["protocol"], h["participant"], s.path.stem,
                                          sum(1 for _ in s.answers()))
    if h["protocol"] in ("pursuit", "search", "free"):
        _references_on(ax, h)
    plot = _PLOTS.get(h["protocol"])
    if plot is not None:
        plot(fig, ax, state)
    ax.set_title(title, fontsize=9)
    out = Path(out)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def _plot_free(fig: Any, ax: Any, state: Any) -> None:
    """The free exploration's matches on the plane (size: confidence)."""
    for m in state.matches:
        ax.plot(m["pitch_db"], m["irregularity_db"], "o", ms=4 + 2 * m["confidence"],
                color="C%d" % (list(state.config.references).index(m["reference"]) % 10))
        ax.annotate(m["reference"], (m["pitch_db"], m["irregularity_db"]), fontsize=7,
                    xytext=(4, 4), textcoords="offset points")
    ax.set_xlabel("pitch (dB re 1 c/mm)")
    ax.set_ylabel("irregularity (dB re 1 decade)")
    ax.text(0.01, 0.99, "o: the matches (size: confidence)\nx: the references' spectral "
            "positions", transform=ax.transAxes, va="top", fontsize=7)


def _plot_quant(fig: Any, ax: Any, state: Any) -> None:
    """The quantization test: similarity against q per reference, or the 3x3
    similarity matrix (design "matrix")."""
    if state.config.design == "matrix":
        _plot_matrix(fig, ax, state)
        return
    by: dict[str, dict[float, list[int]]] = {}
    for r in state.ratings:
        by.setdefault(r["reference"], {}).setdefault(r["quant_db"], []).append(r["similarity"])
    for i, (ref, levels) in enumerate(sorted(by.items())):
        qs = sorted(levels)
        ax.plot([q + 0.08 * (i - 1) for q in qs],
                [sum(levels[q]) / len(levels[q]) for q in qs], "o-", label=ref)
    ax.set_xlabel("quantization q (dB)")
    ax.set_ylabel("similarity (1..5)")
    ax.set_ylim(0.5, 5.5)
    ax.set_xticks(list(state.config.levels_db))
    ax.legend(title="match: %s" % state.config.match_source, fontsize=8, title_fontsize=8)


def _plot_matrix(fig: Any, ax: Any, state: Any) -> None:
    import numpy as np
    refs = list(state.config.references)
    cells: dict[tuple[int, int], list[int]] = {}
    for r in state.ratings:
        cells.setdefault((refs.index(r["reference"]), refs.index(r["match_of"])),
                         []).append(r["similarity"])
    grid = np.full((len(refs), len(refs)), np.nan)
    for (i, j), v in cells.items():
        grid[i, j] = sum(v) / len(v)
    im = ax.imshow(grid, vmin=1, vmax=5, cmap="viridis")
    for (i, j), v in cells.items():
        ax.text(j, i, "%.1f" % grid[i, j], ha="center", va="center", color="w")
    ax.set_xticks(range(len(refs)), ["%s's match" % r for r in refs], fontsize=8)
    ax.set_yticks(range(len(refs)), refs, fontsize=8)
    ax.set_ylabel("reference")
    fig.colorbar(im, ax=ax, label="similarity (1..5)")


def _plot_pursuit(fig: Any, ax: Any, state: Any) -> None:
    """The pursuit's centre, trial by trial."""
    pts = [state.history[0]["centre_before"]] if state.history else \
        [{"u": state.centre.u, "v": state.centre.v}]
    pts += [e["centre_after"] for e in state.history]
    ax.plot([pitch_db(p["u"]) for p in pts], [irregularity_db(p["v"]) for p in pts], "o-")
    ax.annotate("start", (pitch_db(pts[0]["u"]), irregularity_db(pts[0]["v"])))
    ax.set_xlabel("pitch (dB re 1 c/mm)")
    ax.set_ylabel("irregularity (dB re 1 decade)")


def _plot_staircase(fig: Any, ax: Any, state: Any) -> None:
    """The staircase's track, its reversals and threshold."""
    track = state.track
    ax.plot([t["length_mm"] for t in track], "-", color="0.6")
    for i, t in enumerate(track):
        ax.plot(i, t["length_mm"], "o" if t["correct"] else "x",
                color="C2" if t["correct"] else "C3")
    rev = [i for i, t in enumerate(track) if t["reversal"]]
    ax.plot(rev, [track[i]["length_mm"] for i in rev], "s", mfc="none", ms=10,
            label="reversals")
    thr = state.threshold_mm()
    if thr is not None:
        ax.axhline(thr, ls="--", label="threshold %.2f mm" % thr)
    ax.set_xlabel("trial")
    ax.set_ylabel("texel length (mm)")
    ax.legend()


def _plot_search(fig: Any, ax: Any, state: Any) -> None:
    """The search's mean by iteration, with its step size inset."""
    means = [rec["mean_after"] for rec in state.history]
    ax.set_xlabel("pitch (dB re 1 c/mm)")
    ax.set_ylabel("irregularity (dB re 1 decade)")
    if not means:
        return
    xs = [pitch_db(m[0]) for m in means]
    ys = [irregularity_db(m[1]) for m in means]
    ax.plot(xs, ys, "-", color="0.7")
    sc = ax.scatter(xs, ys, c=range(len(means)), cmap="viridis", zorder=3)
    fig.colorbar(sc, ax=ax, label="iteration")
    ax.annotate("end", (xs[-1], ys[-1]))
    # the step size per iteration, inset
    steps = [math.dist(a, b) for a, b in zip(means, means[1:])]
    if steps:
        inset = ax.inset_axes([0.62, 0.08, 0.35, 0.28])
        inset.plot(range(2, len(means) + 1), steps, ".-", lw=0.8)
        inset.set_title("step size", fontsize=7)
        inset.tick_params(labelsize=6)


_PLOTS = {"free": _plot_free, "quant": _plot_quant, "pursuit": _plot_pursuit,
          "staircase": _plot_staircase, "search": _plot_search}


def _references_on(ax: Any, header: dict[str, Any]) -> None:
    """The nine references' positions on the pitch-irregularity plane
    (texelpad.study.references: the spectral model), the session's own
    reference in bold."""
    from .references import positions
    ref = (header["config"].get("reference") or {}).get("name")
    for name, (p, s) in positions().items():
        bold = name == ref
        ax.plot(p, s, "x", color="k" if bold else "0.6", ms=9 if bold else 6)
        ax.annotate(name, (p, s), fontsize=8 if bold else 6, color="k" if bold else "0.5",
                    xytext=(3, -9), textcoords="offset points")


def export(data: str | os.PathLike, out_dir: str | os.PathLike) -> dict[str, Any]:
    """sessions.csv and one PNG per session into out_dir; "broken": the
    sessions left out, [(path, reason)]."""
    files = session_files(data)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    broken: list[tuple[Path, str]] = []
    csv_path, n = write_csv(data, out_dir / "sessions.csv", broken)
    figs = []
    left_out = {p for p, _ in broken}
    for path in files:
        if path in left_out:
            continue
        try:
            s = Session.open(path)
            figs.append(figure(s, out_dir / ("%s-%s.png" % (s.header["participant"],
                                                            path.stem))))
        except (OSError, ValueError, KeyError, TypeError, IndexError, AttributeError) as e:
            broken.append((path, "%s: no figure (%s: %s)" % (path, type(e).__name__,
                                                              str(e)[:200])))
    return {"csv": csv_path, "rows": n, "figures": figs, "broken": broken,
            "sessions": len(files)}
