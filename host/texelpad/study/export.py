"""`texelpad lab export`: session files -> tidy CSV (one row per answer), one
summary figure per session (pursuit: the centre's path on the pitch -
irregularity plane; staircase: the track with its reversals and threshold;
search: the mean's path and step size; mapping: the matches against the
references' central frequencies) and the papers' figures over all sessions
(PAPER_FIGURES: seed 000 Fig. 10-13, 14a/b, 14c, 15; seed 001 Fig. 2-5; seed 003
Table I, also as CSV), each
written only when the data has sessions of its kind. Reads the files only
(never a board).

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
from typing import Any, Sequence

from . import finger
from . import protocols
from .session import Session, SessionError, sessions

COLUMNS = ("participant", "protocol", "session", "config_file", "seed", "n", "time",
           "trial", "answer", "reference", "played_pitch_db", "played_irregularity_db",
           "played_texel_samples", "played_quant_db", "option_played",
           "match_pitch_db", "match_irregularity_db", "confidence", "similarity",
           "quant_db", "match_of", "correct", "length_mm", "chosen",
           # (added with the paper's quantization test and seed 001's mapping: after the
           # columns above, so a reader by position still finds those)
           "source", "pitch_slider", "irregularity_slider",
           # (added with the finger's record, issue 31: seed 001's swipe measures of the
           # question's finger records, study/finger.py; empty where none was recorded)
           "finger_samples", "directional_proportion", "swipe_speed_mm_s",
           "swipe_speed_sd_mm_s",
           # (seed 003's Phase 2, the evaluation: the texture rated, the adjective, its rating)
           "evaluated", "adjective", "adjective_rating")


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
    p = protocols.get(proto)
    state = protocols.start(proto, h["config"], h["seed"])     # what each answer answered
    out = []
    for k, rec in enumerate(s.answers()):
        tex = _texel(rec.get("scene"))
        shown = (rec.get("state") or {}).get("texture")
        if not tex and isinstance(shown, dict) and "pitch_db" in shown:
            tex = shown     # (the rendering, when the scene last felt was the reference alone)
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
        recs = finger.of_question(s.records, k)
        if recs:
            m = finger.measures(recs)
            row.update(finger_samples=m["samples"],
                       **{c: "" if m[f] is None else round(m[f], 6) for c, f in (
                           ("directional_proportion", "directional_proportion"),
                           ("swipe_speed_mm_s", "speed_mm_s"),
                           ("swipe_speed_sd_mm_s", "speed_sd_mm_s"))})
        row.update(p.columns(state, a))            # (from the state before the answer)
        row.update(p.columns_after(protocols.apply(proto, state, a)))
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


def _pyplot() -> Any:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def figure(s: Session, out: str | os.PathLike, state: Any = None) -> Path:
    """The session's summary figure (PNG): its protocol's plot (study/protocols).
    state: the session replayed (replayed here when not given)."""
    plt = _pyplot()
    h = s.header
    if state is None:
        state = protocols.replay(s)
    fig, ax = plt.subplots(figsize=(6, 4.2))
    title = "%s, %s (%s): %d answers" % (h["protocol"], h["participant"], s.path.stem,
                                          sum(1 for _ in s.answers()))
    p = protocols.get(h["protocol"])
    if p.ON_PLANE:
        _references_on(ax, h)
    p.plot(fig, ax, state)
    ax.set_title(title, fontsize=9)
    out = Path(out)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


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
    loaded: list[tuple[Session, Any]] = []
    for path in files:
        if path in left_out:
            continue
        try:
            s = Session.open(path)
            state = protocols.replay(s)
            figs.append(figure(s, out_dir / ("%s-%s.png" % (s.header["participant"],
                                                            path.stem)), state))
            loaded.append((s, state))
        except (OSError, ValueError, KeyError, TypeError, IndexError, AttributeError) as e:
            broken.append((path, "%s: no figure (%s: %s)" % (path, type(e).__name__,
                                                              str(e)[:200])))
    return {"csv": csv_path, "rows": n, "figures": figs, "broken": broken,
            "sessions": len(files), "study_figures": study_figures(loaded, out_dir)}


# --- the papers' figures, over every session of the data folder ---------------------------
# Each is written only when the data has sessions of its kind (with answers), named
# after the paper's figure it follows (../shared/seeds/000_*.txt, 001_*.txt). Each
# *_data function gives exactly what its plot draws (JSON-friendly), so a test can
# check the numbers by hand.

Loaded = list[tuple[Session, Any]]      # (session, its protocol state replayed)


def _of(loaded: Loaded, proto: str) -> Loaded:
    return [(s, st) for s, st in loaded if s.header["protocol"] == proto]


def _mean(xs: Sequence[float]) -> float:
    return sum(xs) / len(xs)


def fig10_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 000 Fig. 10: the free explorations' matches per reference (every
    session's, pitch and irregularity in dB as submitted) and the trained
    rater's choices (study/rater.py)."""
    from .rater import match
    from .references import FAMILIES, REFERENCES
    pitch: dict[str, list[float]] = {}
    irr: dict[str, list[float]] = {}
    for _, st in _of(loaded, "free"):
        for m in st.matches:
            pitch.setdefault(m["reference"], []).append(m["pitch_db"])
            irr.setdefault(m["reference"], []).append(m["irregularity_db"])
    if not pitch:
        return None
    refs = [r for r in REFERENCES if r in pitch]
    return {"references": refs, "families": [FAMILIES[r] for r in refs],
            "pitch_db": [pitch[r] for r in refs], "irregularity_db": [irr[r] for r in refs],
            "rater": [match(r) for r in refs]}


def _guided(loaded: Loaded) -> dict[str, list[dict[str, float]]]:
    """{reference: [end points]} of the finished guided explorations (the
    pursuit's centre as the display plays it: protocols/pursuit.py estimate)."""
    from .question import reference_of
    p = protocols.get("pursuit")
    out: dict[str, list[dict[str, float]]] = {}
    for s, st in _of(loaded, "pursuit"):
        if st.done:
            ref = reference_of(s.header).get("name", "")
            out.setdefault(ref, []).append(p.estimate(st))
    return out


def _free(loaded: Loaded) -> dict[str, list[dict[str, Any]]]:
    """{reference: [the free explorations' matches (pitch_db, irregularity_db, confidence)]}."""
    out: dict[str, list[dict[str, Any]]] = {}
    for _, st in _of(loaded, "free"):
        for m in st.matches:
            out.setdefault(m["reference"], []).append(m)
    return out


def _refs(names: Any) -> list[str]:
    from .references import REFERENCES
    return [r for r in REFERENCES if r in names] + sorted(r for r in names if r not in REFERENCES)


def fig11_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 000 Fig. 11: the guided explorations' choices (end points) per
    reference, central pitch (a) and irregularity (b), with the free
    explorations' matches of the same references superimposed."""
    guided, free = _guided(loaded), _free(loaded)
    if not guided:
        return None
    refs = _refs(guided)
    return {"references": refs,
            "guided_pitch_db": [[m["pitch_db"] for m in guided[r]] for r in refs],
            "guided_irregularity_db": [[m["irregularity_db"] for m in guided[r]] for r in refs],
            "free_pitch_db": [[m["pitch_db"] for m in free.get(r, [])] for r in refs],
            "free_irregularity_db": [[m["irregularity_db"] for m in free.get(r, [])]
                                     for r in refs]}


def confidence_ellipse(points: Sequence[Sequence[float]], level: float = 0.95
                       ) -> dict[str, Any] | None:
    """The confidence ellipse of the mean of 2-D points (Batschelet's, by
    Hotelling's T^2): every m with (m - mean)' S^-1 (m - mean) <= 2 (n - 1) /
    (n (n - 2)) F(level; 2, n - 2), S the sample covariance. Its centre, the
    semi-axes and the angle (degrees) of the first; None below 3 points or for
    a singular S."""
    import numpy as np
    from scipy.stats import f as fdist
    x = np.asarray(points, dtype=float)
    n = len(x)
    if n < 3:
        return None
    cov = np.cov(x.T)
    if not np.isfinite(cov).all() or np.linalg.det(cov) <= 0:
        return None
    k = 2.0 * (n - 1) / (n * (n - 2)) * float(fdist.ppf(level, 2, n - 2))
    vals, vecs = np.linalg.eigh(cov)
    order = np.argsort(vals)[::-1]
    vals, vecs = vals[order], vecs[:, order]
    return {"centre": [float(v) for v in x.mean(axis=0)], "n": n, "level": level,
            "semi_axes": [float(np.sqrt(k * v)) for v in vals],
            "angle_deg": float(np.degrees(np.arctan2(vecs[1, 0], vecs[0, 0])))}


def fig12_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 000 Fig. 12: the family exemplars' choices on the pitch -
    irregularity plane (dB), a) the free explorations' matches, b) the
    guided explorations' end points, each exemplar with its 95 % confidence
    ellipse of the mean (confidence_ellipse; None below 3 choices)."""
    from .quant import EXEMPLARS
    guided, free = _guided(loaded), _free(loaded)
    out: dict[str, Any] = {"exemplars": list(EXEMPLARS)}
    for key, data in (("free", free), ("guided", guided)):
        pts = [[[m["pitch_db"], m["irregularity_db"]] for m in data.get(e, [])]
               for e in EXEMPLARS]
        out[key] = [{"points": p, "ellipse": confidence_ellipse(p)} for p in pts]
    if not any(x["points"] for key in ("free", "guided") for x in out[key]):
        return None
    return out


def fig13_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 000 Fig. 13: each free-exploration match's confidence against
    its distance to the trained rater's choice for the same reference
    (Euclidean in dB: pitch and irregularity, study/rater.py match)."""
    from .rater import match
    pts = []
    for ref, ms in _free(loaded).items():
        r = match(ref)
        for m in ms:
            pts.append({"reference": ref, "confidence": m["confidence"],
                        "distance_db": round(math.hypot(m["pitch_db"] - r["pitch_db"],
                                                        m["irregularity_db"]
                                                        - r["irregularity_db"]), 6)})
    if not pts:
        return None
    return {"points": pts}


def fig14ab_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 000 Fig. 14 a) and b): the similarity of each reference and the
    participant's own match of it - a) the free exploration's (quant
    sessions' own, unquantized trials: designs paper and levels), b) the
    guided exploration's (the similarity matrix's diagonal)."""
    free: dict[str, list[float]] = {}
    guided: dict[str, list[float]] = {}
    for _, st in _of(loaded, "quant"):
        for r in st.ratings:
            if r["reference"] != r["match_of"] or r["quant_db"]:
                continue
            if st.config.design == "matrix":
                guided.setdefault(r["reference"], []).append(r["similarity"])
            elif r["source"] == "own":
                free.setdefault(r["reference"], []).append(r["similarity"])
    if not free and not guided:
        return None
    return {"free": {"references": _refs(free), "similarity": [free[r] for r in _refs(free)]},
            "guided": {"references": _refs(guided),
                       "similarity": [guided[r] for r in _refs(guided)]}}


def fig15_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 000 Fig. 15: per exemplar and q > 0, the change in similarity -
    the quantized trial's rating minus the unquantized one's, same session
    (participant), same reference, same source (own / rater); a session's
    repeats averaged first. Quant sessions of designs paper and levels."""
    changes: dict[str, dict[float, list[float]]] = {}
    for _, st in _of(loaded, "quant"):
        if st.config.design == "matrix":
            continue
        cells: dict[tuple[str, str, float], list[int]] = {}
        for r in st.ratings:
            cells.setdefault((r["reference"], r["source"], float(r["quant_db"])),
                             []).append(r["similarity"])
        for (ref, src, q), v in sorted(cells.items()):
            base = cells.get((ref, src, 0.0))
            if q and base:
                changes.setdefault(ref, {}).setdefault(q, []).append(
                    round(_mean(v) - _mean(base), 6))
    if not changes:
        return None
    from .references import REFERENCES
    refs = [r for r in REFERENCES if r in changes]
    levels = sorted({q for r in refs for q in changes[r]})
    return {"exemplars": refs, "levels_db": levels,
            "changes": [[changes[r].get(q, []) for q in levels] for r in refs]}


def fig14c_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 000 Fig. 14c: the similarity matrix - the mean rating of each
    reference (rows) against each reference's match (columns) over every
    matrix-design quant session (None where nobody rated)."""
    refs: list[str] = []
    cells: dict[tuple[str, str], list[int]] = {}
    for _, st in _of(loaded, "quant"):
        if st.config.design != "matrix":
            continue
        refs += [r for r in st.config.references if r not in refs]
        for r in st.ratings:
            cells.setdefault((r["reference"], r["match_of"]), []).append(r["similarity"])
    if not cells:
        return None
    return {"references": refs,
            "mean": [[round(_mean(cells[(a, b)]), 6) if (a, b) in cells else None
                      for b in refs] for a in refs],
            "n": [[len(cells.get((a, b), [])) for b in refs] for a in refs]}


def fig2_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 001 Fig. 2: every staircase's track (texel length per trial, the
    reversals' trials) and the convergent lengths (threshold_mm: the mean of
    the reversals from threshold_from_reversal on) per condition."""
    tracks = []
    by_cond: dict[str, list[float]] = {}
    for s, st in _of(loaded, "staircase"):
        if not st.track:
            continue
        cond = "distribution given" if s.header["config"].get("distribution") \
            else st.config.condition
        thr = st.threshold_mm()
        tracks.append({"participant": s.header["participant"], "session": s.path.stem,
                       "condition": cond, "length_mm": [t["length_mm"] for t in st.track],
                       "reversals": [i for i, t in enumerate(st.track) if t["reversal"]],
                       "threshold_mm": thr})
        if thr is not None:
            by_cond.setdefault(cond, []).append(thr)
    if not tracks:
        return None
    order = [c for c in ("narrow", "wide") if c in by_cond] + sorted(
        c for c in by_cond if c not in ("narrow", "wide"))
    return {"tracks": tracks, "conditions": order,
            "convergent_mm": [by_cond[c] for c in order]}


def fig3_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 001 Fig. 3: per staircase session with a finger record (a
    subject), its mean |directional proportion| over its trials against its
    convergent texel length (threshold_mm; sessions without one are listed,
    not plotted), the per-trial proportions (the inset: the first two
    sessions), the mean and SD of its swipe speed, and Pearson's R of each
    against the convergent length over the sessions that have both (seed
    001: speed 0.2419, SD 0.3171, directional proportion -0.867)."""
    from scipy.stats import pearsonr
    subjects = []
    for s, st in _of(loaded, "staircase"):
        trials = [finger.measures(finger.of_question(s.records, k)) for k in range(len(st.track))]
        trials = [m for m in trials if m["samples"]]
        if not trials:
            continue
        sub = finger.subject(trials)
        subjects.append({"participant": s.header["participant"], "session": s.path.stem,
                         "convergent_mm": st.threshold_mm(), "trials": len(trials),
                         "directional_proportion": sub["directional_proportion"],
                         "signed_directional_proportion": sub["signed_directional_proportion"],
                         "per_trial": [round(x, 6) for x in sub["per_trial"]],
                         "speed_mm_s": sub["speed_mm_s"], "speed_sd_mm_s": sub["speed_sd_mm_s"]})
    if not subjects:
        return None
    r: dict[str, float | None] = {}
    for key in ("speed_mm_s", "speed_sd_mm_s", "directional_proportion"):
        pts = [(x["convergent_mm"], x[key]) for x in subjects
               if x["convergent_mm"] is not None and x[key] is not None]
        ok = len(pts) >= 3 and len({a for a, _ in pts}) > 1 and len({b for _, b in pts}) > 1
        r[key] = round(float(pearsonr(*zip(*pts))[0]), 4) if ok else None
    return {"subjects": subjects, "r": r, "paper_r": {"speed_mm_s": 0.2419,
                                                      "speed_sd_mm_s": 0.3171,
                                                      "directional_proportion": -0.867}}


def fig4_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 001 Fig. 4 from the mapping sessions (mapping.summary): a) the
    chosen pitch (the lognormal's mean, c/mm) per reference central
    frequency, one list per zeta (a value per session); b) the chosen
    irregularity, normalised over each session's matches, per zeta, one list
    per central frequency."""
    from .bandpass import FC_CPMM, ZETAS
    from .mapping import summary
    # [zeta][fc] -> the mean c/mm chosen, one per session; [fc][zeta] -> normalised I
    a: list[list[list[float]]] = [[[] for _ in FC_CPMM] for _ in ZETAS]
    b: list[list[list[float]]] = [[[] for _ in ZETAS] for _ in FC_CPMM]
    any_match = False
    for _, st in _of(loaded, "mapping"):
        if not st.matches:
            continue
        any_match = True
        sm = summary(st)
        for i, row in enumerate(sm["fig4a"]):
            for j, m in enumerate(row["mean_cpmm"]):
                if m is not None:
                    a[i][j].append(m)
        for i, row in enumerate(sm["fig4b"]):
            for j, x in enumerate(row["irregularity_normalised"]):
                if x is not None:
                    b[i][j].append(x)
    if not any_match:
        return None
    return {"fc_cpmm": list(FC_CPMM), "zetas": list(ZETAS), "fig4a_mean_cpmm": a,
            "fig4b_irregularity_normalised": b}


def fig5_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 001 Fig. 5 from the mapping sessions' ratings (mapping.summary,
    pooled over sessions): a) lowest- vs highest-frequency pairs per zeta,
    b) lowest- vs highest-zeta pairs per central frequency; the self-match
    ratings beside the paper's 8.11 (SD 2.76)."""
    from .bandpass import FC_CPMM, ZETAS
    from .mapping import PAPER, summary
    a: list[list[int]] = [[] for _ in ZETAS]
    b: list[list[int]] = [[] for _ in FC_CPMM]
    own: list[int] = []
    for _, st in _of(loaded, "mapping"):
        if not st.ratings:
            continue
        sm = summary(st)
        for i, row in enumerate(sm["fig5a"]):
            a[i] += row["ratings"]
        for i, row in enumerate(sm["fig5b"]):
            b[i] += row["ratings"]
        own += sm["self"]["ratings"]
    if not (any(a) or any(b) or own):
        return None
    paper = {p["what"]: p["value"] for p in PAPER}
    return {"zetas": list(ZETAS), "fc_cpmm": list(FC_CPMM), "fig5a": a, "fig5b": b,
            "self": own, "paper_self_mean": paper["self_similarity_mean"],
            "paper_self_sd": paper["self_similarity_sd"]}


def _boxes(ax: Any, groups: Sequence[Sequence[float]], positions: Sequence[float], width: float,
           color: str) -> None:
    """Box plots of the groups with data, and every value as a point."""
    have = [(g, x) for g, x in zip(groups, positions) if g]
    if not have:
        return
    ax.boxplot([g for g, _ in have], positions=[x for _, x in have], widths=width,
               patch_artist=True, manage_ticks=False,
               boxprops={"facecolor": color, "alpha": 0.35}, medianprops={"color": "k"})
    for g, x in have:
        ax.plot([x] * len(g), g, ".", color=color, ms=4)


def plot_fig10(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fams = sorted(set(d["families"]), key=d["families"].index)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    xs = list(range(1, len(d["references"]) + 1))
    for ax, key, label in ((axes[0], "pitch_db", "central pitch (dB re 1 c/mm)"),
                           (axes[1], "irregularity_db", "irregularity (dB re 1 decade)")):
        for k, fam in enumerate(fams):
            idx = [i for i, f in enumerate(d["families"]) if f == fam]
            _boxes(ax, [d[key][i] for i in idx], [xs[i] for i in idx], 0.6, "C%d" % k)
            ax.plot([], [], "s", color="C%d" % k, alpha=0.5, label=fam)
        ax.plot(xs, [r[key] for r in d["rater"]], "D", color="C3", mfc="w", ms=7,
                label="trained rater")
        ax.set_xticks(xs, d["references"], rotation=30, fontsize=8)
        ax.set_ylabel(label)
    axes[0].legend(fontsize=7)
    axes[0].set_title("a) central pitch", fontsize=8)
    axes[1].set_title("b) irregularity", fontsize=8)
    fig.suptitle("Free exploration matches per reference (seed 000, Fig. 10); "
                 "n = %d matches" % sum(len(v) for v in d["pitch_db"]), fontsize=9)
    return _save(fig, out)


def plot_fig11(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
    xs = list(range(1, len(d["references"]) + 1))
    for ax, key, label in ((axes[0], "pitch_db", "central pitch (dB re 1 c/mm)"),
                           (axes[1], "irregularity_db", "irregularity (dB re 1 decade)")):
        _boxes(ax, d["guided_" + key], [x - 0.18 for x in xs], 0.32, "C0")
        _boxes(ax, d["free_" + key], [x + 0.18 for x in xs], 0.32, "C1")
        ax.plot([], [], "s", color="C0", alpha=0.5, label="guided exploration")
        ax.plot([], [], "s", color="C1", alpha=0.5, label="free exploration")
        ax.set_xticks(xs, d["references"], fontsize=8)
        ax.set_ylabel(label)
    axes[0].legend(fontsize=7)
    axes[0].set_title("a) central pitch", fontsize=8)
    axes[1].set_title("b) irregularity", fontsize=8)
    fig.suptitle("Guided exploration choices, free exploration superimposed (seed 000, "
                 "Fig. 11)", fontsize=9)
    return _save(fig, out)


def _ellipse(ax: Any, e: dict[str, Any] | None, color: str) -> None:
    if e is None:
        return
    from matplotlib.patches import Ellipse
    ax.add_patch(Ellipse(e["centre"], 2 * e["semi_axes"][0], 2 * e["semi_axes"][1],
                         angle=e["angle_deg"], fill=False, color=color, lw=1.2))


def plot_fig12(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.4), sharex=True, sharey=True)
    for ax, key, title in ((axes[0], "free", "a) free exploration"),
                           (axes[1], "guided", "b) guided exploration")):
        for k, (e, x) in enumerate(zip(d["exemplars"], d[key])):
            pts = x["points"]
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o", color="C%d" % k, ms=4,
                    label="%s (n = %d)" % (e, len(pts)))
            _ellipse(ax, x["ellipse"], "C%d" % k)
        ax.set_xlabel("central pitch (dB re 1 c/mm)")
        ax.set_title(title, fontsize=8)
        ax.legend(fontsize=7)
    axes[0].set_ylabel("irregularity (dB re 1 decade)")
    fig.suptitle("The exemplars' choices with 95 % confidence ellipses of the mean "
                 "(seed 000, Fig. 12)", fontsize=9)
    return _save(fig, out)


def plot_fig13(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    pts = d["points"]
    ax.plot([p["distance_db"] for p in pts], [p["confidence"] for p in pts], "o", ms=4,
            alpha=0.7)
    ax.set_xlabel("distance to the trained rater's choice (dB)")
    ax.set_ylabel("confidence (1..5)")
    ax.set_title("Free exploration: confidence against distance to the trained rater "
                 "(seed 000, Fig. 13)", fontsize=9)
    return _save(fig, out)


def plot_fig14ab(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for ax, key, title in ((axes[0], "free", "a) free exploration matches"),
                           (axes[1], "guided", "b) guided exploration matches")):
        x = d[key]
        xs = list(range(1, len(x["references"]) + 1))
        _boxes(ax, x["similarity"], xs, 0.5, "C0" if key == "free" else "C2")
        if xs:
            ax.set_xticks(xs, x["references"], rotation=30, fontsize=8)
        else:
            ax.text(0.5, 0.5, "no sessions", ha="center", transform=ax.transAxes)
        ax.set_title(title, fontsize=8)
        ax.set_ylim(0.5, 5.5)
    axes[0].set_ylabel("similarity, reference vs its match (1..5)")
    fig.suptitle("Similarity of the references and the participants' own matches "
                 "(seed 000, Fig. 14a/b)", fontsize=9)
    return _save(fig, out)


def _save(fig: Any, out: Path) -> Path:
    plt = _pyplot()
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def plot_fig15(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    n = len(d["exemplars"])
    for k, ref in enumerate(d["exemplars"]):
        off = 0.45 * (k - (n - 1) / 2)
        _boxes(ax, d["changes"][k], [q + off for q in d["levels_db"]], 0.35, "C%d" % k)
        ax.plot([], [], "s", color="C%d" % k, alpha=0.5, label=ref)
    ax.axhline(0.0, ls=":", color="k")
    ax.set_xticks(d["levels_db"], ["%g" % q for q in d["levels_db"]])
    ax.set_xlabel("quantization q (dB)")
    ax.set_ylabel("change in similarity (quantized - unquantized)")
    ax.legend(fontsize=8)
    ax.set_title("Change in similarity with quantization (seed 000, Fig. 15)", fontsize=9)
    return _save(fig, out)


def plot_fig14c(d: dict[str, Any], out: Path) -> Path:
    import numpy as np
    plt = _pyplot()
    refs = d["references"]
    grid = np.array([[np.nan if v is None else v for v in row] for row in d["mean"]])
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    im = ax.imshow(grid, vmin=1, vmax=5, cmap="viridis")
    for i, row in enumerate(d["mean"]):
        for j, v in enumerate(row):
            if v is not None:
                ax.text(j, i, "%.2f\nn=%d" % (v, d["n"][i][j]), ha="center", va="center",
                        color="w", fontsize=8)
    ax.set_xticks(range(len(refs)), ["%s's match" % r for r in refs], fontsize=8)
    ax.set_yticks(range(len(refs)), refs, fontsize=8)
    ax.set_ylabel("reference")
    fig.colorbar(im, ax=ax, label="mean similarity (1..5)")
    ax.set_title("Similarity matrix (seed 000, Fig. 14c)", fontsize=9)
    return _save(fig, out)


def plot_fig2(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2),
                                 gridspec_kw={"width_ratios": [2.2, 1]})
    conds = sorted({t["condition"] for t in d["tracks"]})
    for t in d["tracks"]:
        color = "C%d" % conds.index(t["condition"])
        ax.plot(range(1, len(t["length_mm"]) + 1), t["length_mm"], "-", color=color,
                lw=1, alpha=0.8)
        ax.plot([i + 1 for i in t["reversals"]], [t["length_mm"][i] for i in t["reversals"]],
                "o", mfc="none", color=color, ms=5)
    for k, c in enumerate(conds):
        ax.plot([], [], "-", color="C%d" % k, label=c)
    ax.plot([], [], "o", mfc="none", color="k", label="reversal")
    ax.set_xlabel("trial")
    ax.set_ylabel("texel length (mm)")
    ax.legend(fontsize=8)
    ax.set_title("a) staircases (%d sessions)" % len(d["tracks"]), fontsize=8)
    xs = list(range(1, len(d["conditions"]) + 1))
    for k, c in enumerate(d["conditions"]):
        _boxes(bx, [d["convergent_mm"][k]], [xs[k]], 0.5, "C%d" % conds.index(c))
    if xs:
        bx.set_xticks(xs, d["conditions"])
    else:
        bx.text(0.5, 0.5, "no staircase has reached\nits threshold reversals", ha="center",
                transform=bx.transAxes, fontsize=8)
    bx.set_ylabel("convergent texel length (mm)")
    bx.set_title("b) convergent length per condition", fontsize=8)
    fig.suptitle("Texel-length oddity staircase (seed 001, Fig. 2)", fontsize=9)
    return _save(fig, out)


def plot_fig3(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, (ax, inset) = plt.subplots(1, 2, figsize=(11, 4.4),
                                    gridspec_kw={"width_ratios": [1.6, 1]})
    pts = [x for x in d["subjects"] if x["convergent_mm"] is not None
           and x["directional_proportion"] is not None]
    ax.plot([x["directional_proportion"] for x in pts], [x["convergent_mm"] for x in pts],
            "o", color="C0")
    for x in pts:
        ax.annotate(x["participant"], (x["directional_proportion"], x["convergent_mm"]),
                    fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.set_xlabel("average directional proportion (mean |proportion| over trials)")
    ax.set_ylabel("convergent texel length (mm)")
    ax.set_xlim(-0.02, 1.0)
    r = d["r"]
    ax.set_title("a) each subject: R = %s (paper -0.867); swipe speed R = %s (0.242), its SD "
                 "R = %s (0.317)" % tuple("-" if r[k] is None else "%.3f" % r[k] for k in
                                          ("directional_proportion", "speed_mm_s",
                                           "speed_sd_mm_s")), fontsize=8)
    inset.set_title("b) per trial (the first two subjects; the paper's inset)", fontsize=8)
    fig.suptitle("Swipe directionality (seed 001, Fig. 3)", fontsize=9)
    for k, x in enumerate(d["subjects"][:2]):
        inset.plot(range(1, len(x["per_trial"]) + 1), x["per_trial"], ".-", color="C%d" % (k + 1),
                   label=x["participant"], lw=0.8, ms=3)
    inset.axhline(0, color="k", lw=0.5, ls=":")
    inset.set_ylim(-1.05, 1.05)
    inset.set_xlabel("trial")
    inset.set_ylabel("directional proportion (right - left) / samples")
    inset.legend(fontsize=7)
    if not pts:
        ax.text(0.3, 0.5, "no subject has both a finger record\nand a convergent length",
                transform=ax.transAxes, fontsize=8)
    return _save(fig, out)


def _series(ax: Any, k: int, xs: Sequence[float], rows: Sequence[Sequence[float]],
            label: str) -> None:
    """One series of Fig. 4: every participant's value at each x (nudged by k
    on the log axis so series do not hide each other) and their means, joined."""
    off = 1.08 ** (k - 1)
    for x, vals in zip(xs, rows):
        ax.plot([x * off] * len(vals), vals, "o", color="C%d" % k, ms=4, alpha=0.7)
    avg = [(x * off, _mean(v)) for x, v in zip(xs, rows) if v]
    ax.plot([x for x, _ in avg], [y for _, y in avg], "-", color="C%d" % k, label=label)


def plot_fig4(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4.2))
    fcs, zetas = d["fc_cpmm"], d["zetas"]
    for k, z in enumerate(zetas):
        _series(ax, k, fcs, d["fig4a_mean_cpmm"][k], "zeta %g" % z)
    ax.plot([0.5, 40], [0.5, 40], ":", color="0.4", label="equal")
    for f in fcs:
        ax.axvline(f, ls="--", color="0.85", lw=0.8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("reference central frequency (c/mm)")
    ax.set_ylabel("chosen pitch: lognormal mean (c/mm)")
    ax.legend(fontsize=8)
    ax.set_title("a) pitch", fontsize=8)
    for k, f in enumerate(fcs):
        _series(ax=bx, k=k, xs=zetas, rows=d["fig4b_irregularity_normalised"][k],
                label="%g c/mm" % f)
    for z in zetas:
        bx.axvline(z, ls="--", color="0.85", lw=0.8)
    bx.set_xscale("log")
    bx.set_xlabel("reference zeta")
    bx.set_ylabel("chosen irregularity (normalised per participant)")
    bx.legend(fontsize=8)
    bx.set_title("b) irregularity", fontsize=8)
    fig.suptitle("Texel parameter mapping (seed 001, Fig. 4); lines: means over sessions",
                 fontsize=9)
    return _save(fig, out)


def plot_fig5(d: dict[str, Any], out: Path) -> Path:
    plt = _pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for axis, key, ticks, what in ((ax, "fig5a", d["zetas"], "zeta"),
                                   (bx, "fig5b", d["fc_cpmm"], "central frequency (c/mm)")):
        xs = list(range(1, len(ticks) + 1))
        _boxes(axis, d[key], xs, 0.5, "C0")
        axis.set_xticks(xs, ["%g" % t for t in ticks])
        axis.set_xlabel(what)
        axis.axhline(d["paper_self_mean"], ls="--", color="C3", lw=0.8,
                     label="paper: self-match mean %.2f (SD %.2f)" % (d["paper_self_mean"],
                                                                      d["paper_self_sd"]))
        if d["self"]:
            axis.axhline(_mean(d["self"]), ls=":", color="k", lw=0.8,
                         label="here: self-match mean %.2f (n = %d)" % (_mean(d["self"]),
                                                                      len(d["self"])))
    ax.set_ylabel("similarity (0..10)")
    ax.set_ylim(-0.5, 10.5)
    ax.set_title("a) lowest vs highest frequency, zeta equal", fontsize=8)
    bx.set_title("b) lowest vs highest zeta, frequency equal", fontsize=8)
    ax.legend(fontsize=7, loc="lower left")
    fig.suptitle("Similarity ratings (seed 001, Fig. 5)", fontsize=9)
    return _save(fig, out)


def table1_data(loaded: Loaded) -> dict[str, Any] | None:
    """Seed 003 Table I (Phase 1: texture search) from the finished search
    sessions, per reference: the number of selection iterations (picks), of
    friction tunings (iterations whose answer moved the friction slider:
    PreferenceSearch.tunings) and the time in minutes from the session's start
    to its end (the stop), each mean and SD over the sessions (the paper's
    "M +- SD"; SD None for one session), and the saved textures."""
    from datetime import datetime
    by: dict[str, list[dict[str, Any]]] = {}
    for s, st in _of(loaded, "search"):
        if not st.done or not s.records:
            continue
        ref = (s.header["config"].get("reference") or {}).get("name", "4sin")
        minutes = (datetime.fromisoformat(s.records[-1]["time"])       # (the stop, or its end)
                   - datetime.fromisoformat(s.header["time"])).total_seconds() / 60.0
        by.setdefault(ref, []).append({"iterations": st.iteration, "tunings": st.tunings,
                                       "minutes": minutes, "saved": len(st.saved),
                                       "slider": st.level_slider,
                                       "session": "%s/%s" % (s.header["participant"],
                                                             s.path.stem)})
    if not by:
        return None
    from .references import REFERENCES
    refs = [r for r in REFERENCES if r in by] + sorted(r for r in by if r not in REFERENCES)
    rows = []
    for r in refs:
        runs = by[r]
        row: dict[str, Any] = {"reference": r, "sessions": len(runs),
                               "slider": all(x["slider"] for x in runs)}
        for key in ("iterations", "tunings", "minutes", "saved"):
            xs = [float(x[key]) for x in runs]
            spread = finger.sd(xs)
            row[key] = [round(_mean(xs), 4), None if spread is None else round(spread, 4)]
        rows.append(row)
    return {"rows": rows, "paper": [
        {"reference": "ABS", "iterations": [5.2, 2.77], "tunings": [2.2, 0.84],
         "minutes": [4.44, 1.28]},
        {"reference": "Wood", "iterations": [5.0, 4.53], "tunings": [3.2, 1.64],
         "minutes": [4.35, 2.25]},
        {"reference": "Fiberglass", "iterations": [5.4, 2.70], "tunings": [2.4, 1.14],
         "minutes": [4.38, 0.79]},
        {"reference": "Canvas", "iterations": [4.4, 1.52], "tunings": [2.4, 1.34],
         "minutes": [5.01, 2.2]},
        {"reference": "Stone", "iterations": [3.8, 1.10], "tunings": [1.8, 1.64],
         "minutes": [3.56, 0.79]}]}


def _pm(v: list[Any]) -> str:
    return "%.2f" % v[0] if v[1] is None else "%.2f +- %.2f" % (v[0], v[1])


def plot_table1(d: dict[str, Any], out: Path) -> Path:
    """The table as a figure (and beside it, the same as CSV: out with .csv)."""
    plt = _pyplot()
    head = ["texture", "sessions", "# of iterations", "# of friction tuning", "time (mins)",
            "saved"]
    cells = [[r["reference"], str(r["sessions"]), _pm(r["iterations"]),
              _pm(r["tunings"]) if r["slider"] else "(no slider)", _pm(r["minutes"]),
              _pm(r["saved"])] for r in d["rows"]]
    paper = [["%s (paper)" % r["reference"], "5", _pm(r["iterations"]), _pm(r["tunings"]),
              _pm(r["minutes"]), ""] for r in d["paper"]]
    fig, ax = plt.subplots(figsize=(9, 0.9 + 0.32 * (len(cells) + len(paper) + 1)))
    ax.axis("off")
    t = ax.table(cellText=cells + paper, colLabels=head, loc="center", cellLoc="center")
    t.auto_set_font_size(False)
    t.set_fontsize(8)
    for k in range(len(paper)):
        for j in range(len(head)):
            t[(len(cells) + k + 1, j)].set_text_props(color="0.45")
    ax.set_title("Texture search (seed 003, Table I): M +- SD per texture; grey: the paper's "
                 "five real textures", fontsize=9)
    with open(out.with_suffix(".csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["reference", "sessions", "iterations_mean", "iterations_sd",
                    "tunings_mean", "tunings_sd", "minutes_mean", "minutes_sd", "saved_mean",
                    "saved_sd"])
        for r in d["rows"]:
            w.writerow([r["reference"], r["sessions"], *r["iterations"], *r["tunings"],
                        *r["minutes"], *r["saved"]])
    return _save(fig, out)


PAPER_FIGURES = (("seed000_fig10_matches.png", fig10_data, plot_fig10),
                 ("seed000_fig11_guided.png", fig11_data, plot_fig11),
                 ("seed000_fig12_plane.png", fig12_data, plot_fig12),
                 ("seed000_fig13_confidence.png", fig13_data, plot_fig13),
                 ("seed000_fig14ab_similarity.png", fig14ab_data, plot_fig14ab),
                 ("seed000_fig15_quantization.png", fig15_data, plot_fig15),
                 ("seed000_fig14c_similarity.png", fig14c_data, plot_fig14c),
                 ("seed001_fig2_staircase.png", fig2_data, plot_fig2),
                 ("seed001_fig3_direction.png", fig3_data, plot_fig3),
                 ("seed001_fig4_mapping.png", fig4_data, plot_fig4),
                 ("seed001_fig5_ratings.png", fig5_data, plot_fig5),
                 ("seed003_table1_search.png", table1_data, plot_table1))


def study_figures(loaded: Loaded, out_dir: str | os.PathLike) -> dict[str, Any]:
    """The papers' figures the sessions make: {file name: (path, the data
    plotted)}, only for the figures whose sessions the data has."""
    out: dict[str, Any] = {}
    for name, data_of, plot in PAPER_FIGURES:
        d = data_of(loaded)
        if d is not None:
            out[name] = (plot(d, Path(out_dir) / name), d)
    return out
