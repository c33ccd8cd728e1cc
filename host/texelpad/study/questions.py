"""What a protocol asks now, as the lab shows it: the participant's view (blind:
option labels and the allowed answers, never a parameter value), the scenes
the options play, and the experimenter's view (the parameters, the state).
Built from the protocol's state, the session's header and the board's display;
pure logic (scenes are plain dicts for Board.push; the web layer pushes them).

    q = ask(protocol, state, header, display)
    q.public      -> the participant page's question ({"done": ...})
    q.options     -> scene per option (feel k plays options[k])
    q.detail      -> the experimenter's view (parameters; never sent to the
                     participant page)
    normalise(protocol, q, state, answer)  -> the answer the protocol takes,
                     or ValueError (checked before anything is written)
    slider_scene(state, header, display, a, b, move)
                  -> the scene for a slider setting (the free exploration;
                     the mapping's first phase): sliding(protocol, state)
                     says when a protocol asks with sliders, SLIDER_KEYS
                     names its two values
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

from ..search.preference import candidate_params
from . import rater
from .mapping import SLIDER
from . import scenes as S
from .space import Point, irregularity_db, pitch_db, texel_params


@dataclass
class Question:
    public: dict[str, Any]
    options: list[dict[str, Any]] = field(default_factory=list)
    detail: dict[str, Any] = field(default_factory=dict)
    odd: int | None = None          # the staircase's odd texture (never public)

    @property
    def done(self) -> bool:
        return bool(self.public["done"])


# the two slider values a sliding protocol takes (feel and answer bodies, move records)
SLIDER_KEYS = {"free": ("pitch_db", "irregularity_db"), "mapping": ("pitch", "irregularity")}


def sliding(protocol: str, state: Any) -> bool:
    """Whether the protocol's current question is answered with sliders."""
    return protocol == "free" or (protocol == "mapping" and state.phase == "match")


def reference_of(header: dict[str, Any]) -> dict[str, Any]:
    return header["config"].get("reference") or S.DEFAULT_REFERENCE


def format_of(header: dict[str, Any]) -> int:
    """The texel textures' format: the config's texture_format (2 unless it
    says 1; a header from before the field played format 2)."""
    return S.texture_format(header.get("config"))


def _db(p: Point) -> dict[str, float]:
    return {"pitch_db": round(pitch_db(p.u), 3), "irregularity_db": round(irregularity_db(p.v), 3)}


def ask(protocol: str, state: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if protocol == "pursuit":
        return _pursuit(state, header, display)
    if protocol == "staircase":
        return _staircase(state, header, display)
    if protocol == "search":
        return _search(state, header, display)
    if protocol == "free":
        return _free(state, header, display)
    if protocol == "quant":
        return _quant(state, header, display)
    if protocol == "mapping":
        return _mapping(state, header, display)
    raise ValueError("protocol: unknown %r" % (protocol,))


def _pursuit(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    q = st.next_comparison()
    if q is None:
        return Question({"done": True}, detail={"centre": _db(st.centre),
                                                 "trials": len(st.history)})
    ref = reference_of(header)
    v = format_of(header)
    c = st.config
    sa, sb = c.seeds(header["seed"], q.trial, q.index)
    ta, tb = texel_params(q.a, seed=sa, v=v), texel_params(q.b, seed=sb, v=v)
    if c.presentation == "whole":
        names = ["reference", "A", "B"]
        options = [S.whole(ref, display, name="reference"), S.whole(ta, display, name="A"),
                   S.whole(tb, display, name="B")]
    else:
        names = ["A", "B"]
        options = [S.split(ref, ta, display, name="A"), S.split(ref, tb, display, name="B")]
    return Question({"done": False, "kind": "pair", "trial": q.trial, "index": q.index,
                     "of": [5, 4], "options": names, "answers": ["A", "B", "unsure"],
                     "presentation": c.presentation},
                    options,
                    {"reference": ref, "centre": _db(st.centre), "edge": st.edge,
                     "direction": q.direction, "A": _db(q.a), "B": _db(q.b),
                     "A_is_plus": q.a_is_plus, "seeds": [sa, sb]})


def _staircase(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"threshold_mm": st.threshold_mm(),
                                                 "reversals": st.reversals})
    options, odd = S.staircase_scenes(st.texel_samples(), len(st.track), header["seed"],
                                      display, header["config"].get("distribution")
                                      or st.config.texture(), format_of(header),
                                      st.config.remainder_level,
                                      st.config.fit_mm if st.config.whole_texels else None)
    return Question({"done": False, "kind": "three", "trial": len(st.track),
                     "options": ["1", "2", "3"], "answers": [0, 1, 2],
                     "seconds": st.config.trial_seconds},
                    options,
                    {"length_mm": st.length_mm, "step_mm": st.step_mm,
                     "reversals": len(st.reversals), "odd": odd}, odd=odd)


def _search(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"mean": _mean(st), "saved": st.saved,
                                                 "iterations": st.iteration})
    ref = reference_of(header)
    cands = [candidate_params(x, st.dims, st.texture_seed, format_of(header))
             for x in st.ask()]
    options = [S.split(ref, c, display, name="candidate %d" % (k + 1))
               for k, c in enumerate(cands)]
    answers: list[Any] = [{"choose": k} for k in range(3)] + [{"save": k} for k in range(3)]
    answers.append({"stop": True})
    return Question({"done": False, "kind": "pick", "iteration": st.iteration,
                     "options": ["1", "2", "3"], "answers": answers,
                     "saved": len(st.saved)},
                    options,
                    {"reference": ref, "mean": _mean(st), "sigma": st.sigma,
                     "candidates": cands})


def estimate(protocol: str, st: Any) -> dict[str, float]:
    """Where a guided exploration (its centre) or a search (its mean) ended,
    in dB (clamped to what the display plays: texelpad.study.space)."""
    if protocol == "pursuit":
        p = st.centre
    elif protocol == "search":
        p = Point(st.mean[0], st.mean[1])
    else:
        raise ValueError("estimate: %r has no end point" % (protocol,))
    t = texel_params(p)
    return {"pitch_db": t["pitch_db"], "irregularity_db": t["irregularity_db"]}


def _mean(st: Any) -> dict[str, Any]:
    m = st.mean
    return dict(_db(Point(m[0], m[1])), x=m)


def _free(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"matches": st.matches})
    c = st.config
    return Question({"done": False, "kind": "sliders", "trial": st.trial,
                     "of": len(st.order),
                     "sliders": c.sliders(),
                     "start": list(c.start), "confidence": list(c.confidence),
                     "confidence_input": c.confidence_input,
                     "options": [], "answers": None},
                    [], {"reference": st.reference, "trial": st.trial,
                         "matches": len(st.matches)})


def slider_scene(st: Any, header: dict[str, Any], display: dict[str, Any], a: Any, b: Any,
                 move: int) -> tuple[dict[str, Any], tuple[float, float]]:
    """The scene of a sliding protocol (the free exploration; the mapping's
    first phase) for a slider setting - its reference left, the rendering
    right - and the setting as kept (free: 0.001 dB; mapping: the slider's
    step). ValueError for a value off the sliders."""
    p, s = st.check(a, b)
    return S.split(st.reference_texture(), st.texture(p, s, move, format_of(header)),
                   display, name="rendering"), (p, s)


def _mapping(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"matches": st.matches, "ratings": st.ratings})
    c = st.config
    if st.phase == "match":
        lo, hi = SLIDER
        return Question({"done": False, "kind": "sliders", "trial": st.trial,
                         "of": len(st.order),
                         "sliders": {"pitch": [lo, hi], "irregularity": [lo, hi],
                                     "step": c.step},
                         "start": list(c.start), "confidence": None,
                         "options": [], "answers": None},
                        [], {"reference": st.reference, "phase": "match", "trial": st.trial})
    ref, of = st.current
    lo, hi = c.scale
    tex = st.rating_texture(format_of(header))
    return Question({"done": False, "kind": "rate", "trial": st.trial, "of": len(st.pairs),
                     "options": ["rendering"], "answers": list(range(lo, hi + 1))},
                    [S.split(st.reference_texture(), tex, display, name="rendering")],
                    {"reference": ref, "match_of": of, "phase": "rate", "texture": tex})


def _quant(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"ratings": st.ratings})
    ref, level = st.current
    lo, hi = st.config.scale
    tex = st.texture(format_of(header))
    shown = tex if tex.get("kind") != "samples" else {   # (9,600 values: the record has them)
        "kind": "samples", "rater": st.current_match, "quant_db": level,
        "texel_samples": rater.texel_samples(), "values": len(tex["u16"])}
    rating: dict[str, Any] = {"answers": list(range(lo, hi + 1))}
    if st.config.rating == "slider":    # the app's slider: continuous, at the middle (3) to start
        rating = {"answers": None, "slider": {"range": [lo, hi], "start": (lo + hi) / 2,
                                              "step": 0.01}}
    return Question(dict({"done": False, "kind": "rate", "trial": st.trial,
                          "of": len(st.trials), "options": ["rendering"]}, **rating),
                    [S.split({"kind": "reference", "name": ref}, tex, display,
                             name="rendering")],
                    {"reference": ref, "match_of": st.current_match, "source": st.current_source,
                     "quant_db": level, "texture": shown, "match_source": st.config.match_source})


def normalise(protocol: str, q: Question, state: Any, answer: Any) -> Any:
    """The answer as the protocol takes it, checked against the question
    (ValueError says why; nothing has changed). Answers are compared as JSON,
    so true is not 1 and {"choose": true} is not {"choose": 1}."""
    if q.done:
        raise ValueError("the session is finished")
    if protocol in ("free", "mapping", "quant"):
        return state.checked_answer(answer)
    allowed = q.public["answers"]
    if _js(answer) not in [_js(a) for a in allowed]:
        raise ValueError("answer: expected one of %s, got %s" % (_js(allowed), _js(answer)))
    if protocol == "staircase":
        return answer == q.odd              # what the protocol takes: found or not
    return answer


def _js(x: Any) -> str:
    try:
        return json.dumps(x, sort_keys=True)
    except (TypeError, ValueError):
        return repr(x)
