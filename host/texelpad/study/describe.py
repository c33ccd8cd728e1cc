"""`texelpad lab describe CONFIG`: a study's full trial list before anyone runs
it - what plays on each part of the display in each trial, the order, the
seeds - so a researcher can check a design (and preregister it).

    d = describe("quant-paper", seed=5)          # a dict, JSON-friendly
    print(render_text(d))                        # the table a human reads

Everything here comes from the protocols themselves (the same state machines
and questions.ask / scenes the lab plays), started from the config as the
lab's server starts a session (web/server.py Lab.create: the config file's
"config", its name as config_file, the reference, texture_format). Fixed
designs (free, quant, mapping) are listed trial by trial exactly. Adaptive
ones (pursuit, staircase, search) list what the seed fixes for every trial
and the first question exactly, with the rule for what the answers change.

A display sample array (a rater's logged rendering, a band-pass reference:
9,600 values) is named, not listed: {"kind": "samples", "values": 9600,
"what": "..."}. Pure logic: no link, no web.
"""
from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

from texel.runtime.boards import DX_UM_MAX, POSITIONS_MAX

from . import bandpass
from . import configs as C
from . import protocols
from . import questions as Q
from . import rater
from . import scenes as S
from .session import SessionError

# the TPaD of seeds 000 and 001: 19,200 positions of 5.3 um (texel.runtime.boards)
TPAD_DISPLAY: dict[str, Any] = {"positions": 19200, "dx_um": 5.3}
# staircase trials listed (its length depends on the answers: the simulated participant with
# a 3 mm threshold, texelpad.study.participant, needs a median 61 trials, 95th percentile 72,
# at most 83 over seeds 0..199; each trial's seeds depend on the session's seed and the
# trial's number only, so the list is what any run plays up to here)
STAIRCASE_LISTED = 150


# --- the config ---------------------------------------------------------------------

def load(name_or_config: Any, configs_dir: str | Path | None = None
         ) -> tuple[str, dict[str, Any]]:
    """(name, config file object): a shipped or configs_dir config's name, a
    path to a config .json file, or the object itself. SessionError says why
    not (an unknown name, a file that is missing, not JSON or not a config)."""
    if isinstance(name_or_config, dict):
        return "(given)", C.check("(given)", dict(name_or_config))
    if not isinstance(name_or_config, str) or not name_or_config:
        raise SessionError("config: expected a config's name or a .json file, got %r"
                           % (name_or_config,))
    path = Path(name_or_config)
    if name_or_config.endswith(".json") or "/" in name_or_config:
        if not path.is_file():
            raise SessionError("config %s: no such file" % path)
        if path.stat().st_size > C.FILE_MAX:
            raise SessionError("config %s: over %d bytes" % (path, C.FILE_MAX))
        try:
            obj = json.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, ValueError, RecursionError) as e:
            raise SessionError("config %s: not a JSON config (%s)" % (path, str(e)[:120])) \
                from None
        cf = C.check(path.stem, obj)
        return path.stem, dict(cf, file=str(path))
    return name_or_config, C.load(name_or_config, configs_dir)


def header_config(name: str, cf: dict[str, Any]) -> dict[str, Any]:
    """The "config" a session's header records when the lab starts this
    config (web/server.py Lab.create): the file's config, its name, the
    reference (the pursuit's and the search's, 4sin by default) and the
    texture format (2 unless it says 1)."""
    proto = cf["protocol"]
    config = dict(cf.get("config", {}))
    config["config_file"] = name
    if proto in ("pursuit", "search"):
        config["reference"] = cf.get("reference") or dict(S.DEFAULT_REFERENCE)
    config["texture_format"] = S.texture_format(config)
    return config


def full_config(proto: str, state: Any, header: dict[str, Any]) -> dict[str, Any]:
    """Every choice field: what a session's header records
    (protocols.resolved: the Config's fields, defaults included, and the
    scenes' keys), plus the search's own fields and the staircase's stimulus
    as it plays (JSON: tuples as lists)."""
    if proto != "search":
        out = protocols.resolved(proto, state, header)
        if proto == "staircase" and "distribution" not in out:
            out["distribution"] = state.config.texture()
        return out
    fields = {k: getattr(state, k) for k in ("dims", "x0", "sigma0", "texture_seed",
                                               "texture_format")}
    fields["x0"] = fields["x0"] if fields["x0"] is not None else [0.5] * len(state.dims)
    out = dict(fields, **{k: v for k, v in header.items() if k in protocols.SCENE_KEYS})
    return json.loads(json.dumps(out))


def parse_display(text: str) -> dict[str, Any]:
    """"positions" or "positions,dx_um" (e.g. 19200,5.3) -> a display dict;
    ValueError names the value and the range."""
    parts = [p.strip() for p in str(text).split(",")]
    if not 1 <= len(parts) <= 2:
        raise ValueError("display: expected positions[,dx_um], got %r" % (text,))
    try:
        n = int(parts[0])
        dx = float(parts[1]) if len(parts) == 2 else TPAD_DISPLAY["dx_um"]
    except ValueError:
        raise ValueError("display: expected positions[,dx_um] (numbers), got %r"
                         % (text,)) from None
    if not 1 <= n <= POSITIONS_MAX:
        raise ValueError("display: positions must be 1 .. %d, got %d" % (POSITIONS_MAX, n))
    if not 0 < dx <= DX_UM_MAX:
        raise ValueError("display: dx_um must be in (0, %g], got %r" % (DX_UM_MAX, dx))
    return {"positions": n, "dx_um": dx}


# --- scenes as text ------------------------------------------------------------------

def _where(start: float, end: float, total: float) -> str:
    half = round(total / 2, 6)
    if start == 0 and end == total:
        return "whole display"
    if start == 0 and end == half:
        return "left half"
    if start == half and end == total:
        return "right half"
    return "span"


def _texture(t: dict[str, Any], what: str | None) -> dict[str, Any]:
    if t.get("kind") == "samples":
        return {"kind": "samples", "fit": t.get("fit"), "values": len(t.get("u16", ())),
                "what": what or "display samples"}
    return json.loads(json.dumps(t))


def scene(sc: dict[str, Any], display: dict[str, Any], what: str | None = None
          ) -> list[dict[str, Any]]:
    """A scene's regions: where (left half / right half / whole display /
    a span), start and end mm, the texture (a samples array named by `what`)."""
    total = round(display["positions"] * display["dx_um"] / 1000.0, 6)
    return [{"where": _where(r["start_mm"], r["end_mm"], total), "start_mm": r["start_mm"],
             "end_mm": r["end_mm"], "texture": _texture(r["texture"], what)}
            for r in sc["regions"]]


def _option(name: str, sc: dict[str, Any], display: dict[str, Any],
            what: str | None = None) -> dict[str, Any]:
    return {"option": name, "regions": scene(sc, display, what)}


def _split(name: str, left: dict[str, Any], right: dict[str, Any],
           display: dict[str, Any]) -> dict[str, Any]:
    """An option whose textures are described, not built (they depend on
    answers): the scene's geometry is scenes.split's."""
    sc = S.split({"kind": "reference", "name": "-"}, {"kind": "texel"}, display)
    regs = scene(sc, display)
    regs[0]["texture"], regs[1]["texture"] = left, right
    return {"option": name, "regions": regs}


# --- the protocols -------------------------------------------------------------------

def _free(st: Any, header: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    c = st.config
    trials = []
    while not st.done:
        sc, _ = Q.slider_scene(st, header, display, c.start[0], c.start[1], 0)
        trials.append({"trial": st.trial, "reference": st.reference,
                       "options": [_option("sliders", sc, display)], "move": 0,
                       "answer": "pitch_db, irregularity_db (sliders), confidence %d .. %d"
                                 % tuple(c.confidence)})
        st.answer({"pitch_db": c.start[0], "irregularity_db": c.start[1],
                   "confidence": c.confidence[0]})
    return {"trials": trials, "rules": [
        "every slider change re-draws the rendering with a fresh texture seed drawn from "
        "(session seed, trial, move) (study/free.py Free.texture); move 0 is listed",
        "the sliders start at pitch %g dB, irregularity %g dB (%s slider)"
        % (c.start[0], c.start[1], c.irregularity_slider)]}


def _quant(st: Any, header: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    c = st.config
    v = Q.format_of(header)
    phases = st.phases                      # the rater renderings' start phases (quant.py)
    trials = []
    for k, p in enumerate(st.plan):
        ref, of, src, q = p["reference"], p["match_of"], p["source"], p["quant_db"]
        left = {"kind": "reference", "name": ref}
        if src == "rater":
            what = "the rater's logged sequence of %s quantized at %g dB" % (of, q)
            if c.rater_rows != "by_texture":
                what = ("the rater's sequence of %s, which a session of rater_rows %r played "
                        "beside %s, quantized at %g dB" % (rater.played(of, c.rater_rows),
                                                          c.rater_rows, of, q))
            if phases is not None:
                what += ", start phase %.6f cycle" % phases[k]
            right = {"kind": "samples", "fit": "tile", "what": what,
                     "values": len(rater.pitches(of)) * rater.texel_samples()}
        elif c.matches is None:
            right = {"kind": "texel", "what": "the participant's own match of %s (from their "
                     "free exploration)" % of, "quant_db": q,
                     "seed": "the felt texture's (else %d)" % st.texture_seeds[of]}
        else:
            right = dict(st.own_texture(of, q, v), kind="texel")
        trials.append({"trial": k, "reference": ref, "match_of": of, "source": src,
                       "quant_db": q, "options": [_split("rendering", left, right, display)],
                       "answer": "similarity %d .. %d" % tuple(c.scale)})
    rules = ["design %r, order %r: the trial order is drawn from the session's seed"
             % (c.design, c.order) if c.order == "seeded" else
             "design %r, order 'lab': the app's fixed compareOrder" % c.design]
    if c.matches is None:
        rules.append("no matches in the config: the lab starts it with matches_from (the "
                     "participant's free exploration); each own trial plays the texture felt "
                     "when that match was submitted")
    return {"trials": trials, "rules": rules}


def _mapping(st: Any, header: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    c = st.config
    trials = []
    while st.phase == "match":
        ref = st.reference
        sc, _ = Q.slider_scene(st, header, display, c.start[0], c.start[1], 0)
        what = "band-pass reference %s seed %d" % (ref, c.reference_seed)
        trials.append({"trial": st.trial, "phase": "match", "reference": ref,
                       "options": [_option("sliders", sc, display, what)], "move": 0,
                       "answer": "pitch, irregularity (sliders 0 .. 100)"})
        st.answer({"pitch": c.start[0], "irregularity": c.start[1]})
    for k, (ref, of) in enumerate(st.pairs):
        left = bandpass.board_texture(ref) if c.reference_play == "board" else {
            "kind": "samples", "fit": "tile", "values": bandpass.HALF_SCREEN,
            "what": "band-pass reference %s seed %d" % (ref, c.reference_seed)}
        right = {"kind": "texel", "what": "the participant's own match of %s (from phase 1)"
                 % of, "texel_samples": c.texel_samples, "seed": st.rating_seeds[of],
                 "min_cpmm": c.min_cpmm, "phase": c.phase, "v": Q.format_of(header)}
        trials.append({"trial": k, "phase": "rate", "reference": ref, "match_of": of,
                       "options": [_split("rendering", left, right, display)],
                       "answer": "similarity %d .. %d" % tuple(c.scale)})
    return {"trials": trials, "rules": [
        "phase 1: every slider change re-draws with a fresh seed from (session seed, trial, "
        "move); move 0 (the sliders' start) is listed",
        "phase 2 plays each participant's phase-1 match with the seed listed (one per match)"]}


def _pursuit(st: Any, header: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    c = st.config
    seed = header["seed"]
    first = st.trial
    out = []
    while not st.done:
        q = st.next_comparison()
        sa, sb = c.seeds(seed, q.trial, q.index)
        entry: dict[str, Any] = {"trial": q.trial, "index": q.index, "direction": q.direction,
                                 "A": "+" + q.direction if q.a_is_plus else "-" + q.direction,
                                 "B": "-" + q.direction if q.a_is_plus else "+" + q.direction,
                                 "seeds": [sa, sb]}
        if q.trial == first:            # the centre moves only after a trial's 4th answer
            qq = Q.ask("pursuit", st, header, display)
            entry["options"] = [_option(n, sc, display)
                                for n, sc in zip(qq.public["options"], qq.options)]
            entry["A_db"], entry["B_db"] = qq.detail["A"], qq.detail["B"]
        else:
            ref = [_option("reference", S.whole(Q.reference_of(header), display), display)] \
                if c.presentation == "whole" else []
            where = "whole display" if c.presentation == "whole" else "right half"
            entry["options"] = ref + [
                {"option": n, "where": where, "seed": s, "v": Q.format_of(header),
                 "depends": "the point centre %s edge/4 * d_%s"
                 % ("+" if (n == "A") == q.a_is_plus else "-", q.direction)}
                for n, s in (("A", sa), ("B", sb))]
        out.append(entry)
        st.answer("unsure")             # (no move: the order and sides are the seed's only)
    return {"trials": out, "rules": [
        "the order of the 4 directions and the A/B sides are drawn from the session's seed "
        "alone; the texture seeds from (seed, trial, index)",
        "answers move the centre: centre += (sum r_k d_k) * %.6f (r_k = +1 / -1 / 0 for the "
        "+d_k point, its opposite, unsure), clamped to the unit square; edge -= %g; A and B "
        "are centre +- edge/4 * d_k; it stops when edge < %g (5 trials, 20 comparisons)"
        % (c.step, c.edge_step, c.stop_below)]}


def _staircase(st: Any, header: dict[str, Any], display: dict[str, Any],
               listed: int) -> dict[str, Any]:
    seed, v = header["seed"], Q.format_of(header)
    dist = header.get("config", {}).get("distribution") or st.config.texture()
    trials = []
    q0 = Q.ask("staircase", st, header, display)
    for k in range(listed):
        scs, odd = S.staircase_scenes(st.texel_samples(), k, seed, display, dist, v,
                                      st.config.remainder_level)
        seeds = [sc["regions"][0]["texture"]["seed"] for sc in scs]
        entry: dict[str, Any] = {"trial": k, "seeds": seeds, "odd": odd + 1}
        if k == 0:
            entry["length_mm"] = st.length_mm
            entry["texel_samples"] = st.texel_samples()
            entry["options"] = [_option(n, sc, display)
                                for n, sc in zip(q0.public["options"], q0.options)]
        trials.append(entry)
    c = st.config
    return {"trials": trials, "rules": [
        "each trial's three texture seeds and the odd one's position (1..3) come from "
        "(session seed, trial) alone; the first %d trials are listed" % listed,
        "the texel length depends on the answers: 1-up-%d-down from %g mm in %g mm steps, "
        "%g mm after %d reversals, never below %g mm; it stops after %d reversals; threshold "
        "= mean length at reversals %d.." % (c.down_after, c.start_mm, c.step_mm,
                                             c.fine_step_mm, c.fine_after_reversals,
                                             c.floor_mm, c.stop_after_reversals,
                                             c.threshold_from_reversal),
        "each texture fills the display with whole texels of the trial's length, the rest "
        "at level %g" % c.remainder_level]}


def _search(st: Any, header: dict[str, Any], display: dict[str, Any]) -> dict[str, Any]:
    q = Q.ask("search", st, header, display)
    first = {"iteration": 0, "options": [_option(n, sc, display)
                                         for n, sc in zip(q.public["options"], q.options)],
             "candidates": q.detail["candidates"]}
    return {"trials": [first], "rules": [
        "the seed fixes CMA-ES's generator (cma seed = session seed + 1), the ranking's "
        "shuffle of the two not chosen (random.Random(seed)) and so, for given answers, "
        "every candidate; every candidate is rendered with texture seed %d"
        % st.texture_seed,
        "the candidates after the first iteration depend on the picks (CMA-ES, lambda 3, "
        "mirrored, sigma0 %g); the participant stops when satisfied" % st.sigma0]}


_TRIALS: dict[str, Callable[..., dict[str, Any]]] = {
    "free": _free, "quant": _quant, "mapping": _mapping, "pursuit": _pursuit,
    "search": _search}


def describe(name_or_config: Any, seed: int | None = None,
             display: dict[str, Any] | None = None, configs_dir: str | Path | None = None,
             staircase_trials: int = STAIRCASE_LISTED) -> dict[str, Any]:
    """The study's full trial list (module docstring). seed None: the
    config's seed; a config without one has its session's seed drawn at
    start, and seed 0 is described (said in "seed_source")."""
    name, cf = load(name_or_config, configs_dir)
    if seed is None:
        seed = cf.get("seed")
        source = "the config's" if seed is not None else \
            "none given: a session's seed is drawn at its start; seed 0 described"
        seed = seed or 0
    else:
        source = "given"
    if isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed < 1 << 31:
        raise SessionError("seed: expected an int in [0, 2^31), got %r" % (seed,))
    display = dict(display or TPAD_DISPLAY)
    proto = cf["protocol"]
    hc = header_config(name, cf)
    header = {"protocol": proto, "config": hc, "seed": seed}
    state = protocols.start(proto, hc, seed)
    config = full_config(proto, state, hc)
    if proto == "staircase":
        body = _staircase(state, header, display, staircase_trials)
    else:
        body = _TRIALS[proto](state, header, display)
    fixed = proto in ("free", "quant", "mapping")
    for k, t in enumerate(body["trials"]):
        t["question"] = k + 1           # the answers before it, plus one
    return {"config_name": name, "file": cf.get("file"), "protocol": proto,
            "title": cf.get("title", protocols.TITLES[proto]), "note": cf.get("note"),
            "seed": seed, "seed_source": source, "display": display, "config": config,
            "design": "fixed" if fixed else "adaptive", "trials": body["trials"],
            "trial_count": len(body["trials"]) if fixed else None, "rules": body["rules"]}


# --- the text --------------------------------------------------------------------------

def texture_text(t: dict[str, Any]) -> str:
    """One texture as a short line."""
    kind = t.get("kind")
    if kind == "reference":
        return "reference %s" % t.get("name")
    if kind == "samples":
        return "samples: %s (%s values)" % (t.get("what"), format(t.get("values", 0), ","))
    if kind == "constant":
        return "constant level %g" % t.get("level", 0)
    parts = [t["what"]] if "what" in t else []
    if isinstance(t.get("pitch_db"), (int, float)):
        parts.append("pitch %.3f dB, irregularity %.3f dB" % (t["pitch_db"],
                                                               t["irregularity_db"]))
    for key, fmt in (("texel_samples", "%s-sample texels"), ("quant_db", "q %s dB"),
                     ("min_cpmm", "above %s c/mm"), ("phase", "phase %s"),
                     ("gain", "gain %s"), ("seed", "seed %s"), ("v", "format %s")):
        if t.get(key) is not None and not (key == "quant_db" and not t[key]):
            parts.append(fmt % (t[key],))
    return "texel: " + ", ".join(parts)


def _trial_title(d: dict[str, Any], t: dict[str, Any]) -> str:
    keys = [k for k in ("phase", "reference", "move", "match_of", "source", "quant_db",
                        "direction",
                        "A", "B", "seeds", "odd", "length_mm", "A_db", "B_db")
            if k in t]
    head = "question %d%s" % (t["question"], " of %d" % d["trial_count"]
                              if d["trial_count"] else "")
    if "iteration" in t:
        head += " (iteration %d)" % (t["iteration"] + 1)
    else:
        head += " (trial %d%s)" % (t["trial"] + 1, ".%d" % (t["index"] + 1)
                                   if "index" in t else "")
    return head + ": " + ", ".join("%s %s" % (k, json.dumps(t[k])) for k in keys)


def render_text(d: dict[str, Any]) -> str:
    """The description as a table a human reads."""
    lines = ["%s (%s): %s" % (d["config_name"], d["protocol"], d["title"]),
             "seed %d (%s); display %s positions x %g um" % (
                 d["seed"], d["seed_source"], format(d["display"]["positions"], ","),
                 d["display"]["dx_um"]),
             "config: " + json.dumps(d["config"], sort_keys=True)]
    if d.get("note"):
        lines.append("note: " + d["note"])
    lines.append("%s design: %s" % (d["design"], "%d trials" % d["trial_count"]
                                    if d["trial_count"] else "the seed's part of every trial "
                                    "and the first question exactly"))
    lines += ["rule: " + r for r in d["rules"]]
    lines.append("")
    for t in d["trials"]:
        lines.append(_trial_title(d, t))
        for o in t.get("options", []):
            if "regions" not in o:
                lines.append("    %-10s %-13s %23s  %s, seed %s, format %s"
                             % (o["option"], o["where"], "", o["depends"], o["seed"], o["v"]))
                continue
            for r in o["regions"]:
                lines.append("    %-10s %-13s %8.3f .. %8.3f mm  %s"
                             % (o["option"][:10], r["where"], r["start_mm"], r["end_mm"],
                                texture_text(r["texture"])))
        if "answer" in t:
            lines.append("    answer: %s" % t["answer"])
    return "\n".join(lines) + "\n"
