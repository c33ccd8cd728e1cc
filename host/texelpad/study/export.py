"""`texelpad lab export`: session files -> tidy CSV (one row per answer) and one
summary figure per session (pursuit: the centre's path on the pitch -
irregularity plane; staircase: the track with its reversals and threshold;
search: the mean's path and step size). Reads the files only (never a board).
"""
from __future__ import annotations

import csv
import math
import os
from pathlib import Path
from typing import Any

from . import protocols
from .session import Session, sessions
from .space import irregularity_db, pitch_db

COLUMNS = ("participant", "protocol", "session", "n", "time", "answer", "correct",
           "option_played", "right_pitch_db", "right_irregularity_db", "right_texel_samples",
           "seed")


def _texture(rec: dict[str, Any]) -> dict[str, Any]:
    scene = rec.get("scene") or {}
    regs = scene.get("regions") or []
    tex = regs[-1]["texture"] if regs else {}
    return tex if tex.get("kind") == "texel" else {}


def rows(s: Session) -> list[dict[str, Any]]:
    h = s.header
    out = []
    for rec in s.answers():
        tex = _texture(rec)
        a = rec.get("answer")
        out.append({"participant": h["participant"], "protocol": h["protocol"],
                    "session": s.path.stem, "n": rec.get("n"), "time": rec.get("time"),
                    "answer": a if not isinstance(a, dict) else "%s %s" % next(iter(a.items())),
                    "correct": a if isinstance(a, bool) else "",
                    "option_played": rec.get("playing", ""),
                    "right_pitch_db": tex.get("pitch_db", ""),
                    "right_irregularity_db": tex.get("irregularity_db", ""),
                    "right_texel_samples": tex.get("texel_samples", ""), "seed": h["seed"]})
    return out


def write_csv(data: str | os.PathLike, out: str | os.PathLike) -> tuple[Path, int]:
    """Every session under data as one CSV (written beside, then renamed)."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(out.name + ".tmp")
    n = 0
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        for path in sessions(data):
            for r in rows(Session.open(path)):
                w.writerow(r)
                n += 1
    os.replace(tmp, out)
    return out, n


def figure(s: Session, out: str | os.PathLike) -> Path:
    """The session's summary figure (PNG)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    h = s.header
    state = protocols.replay(s)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    title = "%s, %s (%s): %d answers" % (h["protocol"], h["participant"], s.path.stem,
                                          len(s.records))
    if h["protocol"] == "pursuit":
        pts = [state.history[0]["centre_before"]] if state.history else \
            [{"u": state.centre.u, "v": state.centre.v}]
        pts += [e["centre_after"] for e in state.history]
        ax.plot([pitch_db(p["u"]) for p in pts], [irregularity_db(p["v"]) for p in pts], "o-")
        ax.annotate("start", (pitch_db(pts[0]["u"]), irregularity_db(pts[0]["v"])))
        ax.set_xlabel("pitch (dB re 1 c/mm)")
        ax.set_ylabel("irregularity (dB re 1 decade)")
    elif h["protocol"] == "staircase":
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
    elif h["protocol"] == "search":
        means = [rec["mean_after"] for rec in state.history]
        ax.set_xlabel("pitch (dB re 1 c/mm)")
        ax.set_ylabel("irregularity (dB re 1 decade)")
        if means:
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
    ax.set_title(title, fontsize=9)
    out = Path(out)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def export(data: str | os.PathLike, out_dir: str | os.PathLike) -> dict[str, Any]:
    """sessions.csv and one PNG per session into out_dir."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    csv_path, n = write_csv(data, out_dir / "sessions.csv")
    figs = []
    for path in sessions(data):
        s = Session.open(path)
        figs.append(figure(s, out_dir / ("%s-%s.png" % (s.header["participant"], path.stem))))
    return {"csv": csv_path, "rows": n, "figures": figs}
