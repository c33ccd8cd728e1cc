"""Seed 003's Phase 2: other participants rate the searches' saved textures -
three adjectives per texture, then (or first) each virtual texture's
similarity to its real one. Its state: study/evaluate.py."""
from __future__ import annotations

from typing import Any

from .. import evaluate as EV
from .. import scenes as S
from ..describing import whole
from ..free import rating_input
from ..question import Question
from .base import Protocol, tuples


def _scene_texture(t: dict[str, Any]) -> dict[str, Any]:
    tex = t["texture"]
    return tex if tex.get("kind") else dict(tex, kind="texel")


def _ask(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"ratings": st.ratings})
    step, t, adjective = st.current
    public: dict[str, Any] = {"done": False, "kind": "rate", "trial": st.trial,
                              "of": len(st.plan), "presentation": "whole", "step": step,
                              **rating_input(st.config.scale, st.config.rating)}
    if step == "adjective":
        public.update(options=["texture"], adjective=adjective,
                      anchors=list(EV.ADJECTIVES[adjective]))
        scenes = [S.whole(_scene_texture(t), display, name="texture")]
    else:
        public["options"] = ["real", "virtual"]
        scenes = [S.whole(st.real_of(t["reference"]), display, name="real"),
                  S.whole(_scene_texture(t), display, name="virtual")]
    return Question(public, scenes, {"step": step, "texture": t["name"],
                                     "reference": t["reference"], "source": t["source"],
                                     "adjective": adjective})


EXAMPLE = {"name": "VTp (a stopped search's last saved texture)", "reference": "4sin",
           "texture": {"pitch_db": 7.9, "irregularity_db": -6.1, "seed": 0}}


def _trials(st: Any, header: dict[str, Any], display: dict[str, Any],
            listed: int = 0) -> dict[str, Any]:
    c = st.config
    if c.textures is None:          # (listed for one example saved texture of 4sin)
        st = EV.Evaluate(st.seed, EV.Config(**dict(
            {f: getattr(c, f) for f in c.__dataclass_fields__}, textures=(EXAMPLE,))), st.fmt)
    by = {t["name"]: t for t in st.textures}
    trials = []
    for k, p in enumerate(st.plan):
        t = by[p["texture"]]
        if p["step"] == "adjective":
            options = [whole("texture", _scene_texture(t), display)]
            answer = "%s %d (%s) .. %d (%s)" % ((p["adjective"], c.scale[0])
                                                 + (EV.ADJECTIVES[p["adjective"]][0],)
                                                 + (c.scale[1],)
                                                 + (EV.ADJECTIVES[p["adjective"]][1],))
        else:
            options = [whole("real", st.real_of(t["reference"]), display),
                       whole("virtual", _scene_texture(t), display)]
            answer = "similarity %d (completely different) .. %d (completely the same)" \
                % tuple(c.scale)
        trials.append(dict(p, trial=k, options=options, answer=answer))
    rules = ["the textures' order (adjectives) and the pairs' order (similarity) are drawn "
             "from the session's seed; steps %r: %s first" % (c.steps, st.first.split("_")[0])]
    if c.textures is None:
        rules.append("no textures in the config: the lab starts it with matches_from (stopped "
                     "searches: the texture each saved last); listed here for one example "
                     "saved texture of 4sin")
    return {"trials": trials, "rules": rules}


def _plot(fig: Any, ax: Any, state: Any) -> None:
    """Similarity of each virtual texture to its real one, and the adjectives."""
    sims = [r for r in state.ratings if r["step"] == "similarity"]
    names = [r["texture"] for r in sims]
    ax.barh(range(len(sims)), [r["rating"] for r in sims],
            color=["C2" if r["source"] == "data" else "C0" for r in sims])
    ax.set_yticks(range(len(sims)), names, fontsize=7)
    lo, hi = state.config.scale
    ax.set_xlim(lo - 0.2, hi + 0.2)
    ax.set_xlabel("similarity to the real texture (%d .. %d)" % (lo, hi))
    ax.set_title("green: data-driven stand-in (VTd); blue: preference-driven (VTp)",
                 fontsize=8)


class EvaluateProtocol(Protocol):
    NAME = "evaluate"
    TITLE = "texture evaluation: the searches' textures rated (seed 003, Phase 2)"
    TAKES_SAVED = True              # its textures: matches_from names stopped searches
    FIXED = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return EV.Evaluate(seed, EV.Config(**tuples(config)), fmt)

    def normalise(self, q: Question, state: Any, answer: Any) -> Any:
        return state.checked_answer(answer)

    def simulate(self, who: Any, state: Any) -> Any:
        """The simulated participant: similarity from how far the virtual
        texture's point is from the reference's, adjectives the middle."""
        import math
        step, t, _ = state.current
        lo, hi = state.config.scale
        if step == "adjective":
            return (lo + hi) // 2
        from ..references import position
        p, s = position(t["reference"])
        tex = t["texture"]
        d = math.hypot(tex["pitch_db"] - p, tex["irregularity_db"] - s)
        return int(min(hi, max(lo, round(hi - d / 4.0))))

    def columns(self, state: Any, a: Any) -> dict[str, Any]:
        step, t, adjective = state.current
        out: dict[str, Any] = {"trial": state.trial, "reference": t["reference"],
                               "evaluated": t["name"], "source": t["source"]}
        if step == "similarity":
            out["similarity"] = a
        else:
            out.update(adjective=adjective, adjective_rating=a)
        return out


PROTOCOL = EvaluateProtocol()
