"""The preference-driven search (seed 003): CMA-ES over the texel space, the
participant picking the closest of three candidates (or saving one, or
stopping). Its state: texelpad.search.preference.PreferenceSearch."""
from __future__ import annotations

import json
import math
from typing import Any

from ...search.preference import LEVEL, PreferenceSearch, candidate_params, check_level
from .. import scenes as S
from ..describing import option
from ..question import Question, played_db, format_of, mean_of, reference_of
from ..space import Point, irregularity_db, pitch_db
from .base import SCENE_KEYS, Protocol, tuples


def _ask(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"mean": mean_of(st), "saved": st.saved,
                                                 "iterations": st.iteration})
    ref = reference_of(header)
    cands = [candidate_params(x, st.dims, st.texture_seed, format_of(header), st.level)
             for x in st.ask()]
    options = [S.split(ref, c, display, name="candidate %d" % (k + 1))
               for k, c in enumerate(cands)]
    answers: list[Any] = [{"choose": k} for k in range(3)] + [{"save": k} for k in range(3)]
    answers.append({"stop": True})
    public: dict[str, Any] = {"done": False, "kind": "pick", "iteration": st.iteration,
                              "options": ["1", "2", "3"], "answers": answers,
                              "saved": len(st.saved)}
    if st.level_slider:         # seed 003's friction slider: the map's gain of all three
        public["level"] = {"range": list(LEVEL), "start": st.level, "step": 0.01}
    return Question(public,
                    options,
                    {"reference": ref, "mean": mean_of(st), "sigma": st.sigma,
                     "candidates": cands})


def _trials(st: Any, header: dict[str, Any], display: dict[str, Any],
            listed: int = 0) -> dict[str, Any]:
    q = _ask(st, header, display)
    first = {"iteration": 0, "options": [option(n, sc, display)
                                         for n, sc in zip(q.public["options"], q.options)],
             "candidates": q.detail["candidates"]}
    return {"trials": [first], "rules": [
        "the seed fixes CMA-ES's generator (cma seed = session seed + 1), the ranking's "
        "shuffle of the two not chosen (random.Random(seed)) and so, for given answers, "
        "every candidate; every candidate is rendered with texture seed %d"
        % st.texture_seed,
        "the candidates after the first iteration depend on the picks (CMA-ES, lambda 3, "
        "mirrored, sigma0 %g, update %r); the participant stops when satisfied"
        % (st.sigma0, st.cma_update)] + (
        ["a friction slider (the map's gain %g .. %g, from %g) sets the level of all three "
         "candidates; each choice or save carries the level that played"
         % (LEVEL[0], LEVEL[1], st.level_start)] if st.level_slider else [])}


def _plot(fig: Any, ax: Any, state: Any) -> None:
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


class SearchProtocol(Protocol):
    NAME = "search"
    TITLE = "preference-driven search: CMA-ES (seed 003)"
    REFERENCE_CHOSEN = True
    GIVES_MATCHES = "end point"
    GIVES_SAVED = True          # its last saved texture: seed 003's Phase 2 (evaluate)
    ON_PLANE = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return PreferenceSearch(seed, texture_format=fmt, **tuples(config))

    FEEL_KEYS = ("level",)          # the friction slider's setting, sent with a feel

    def apply(self, state: Any, answer: Any) -> dict[str, Any]:
        from ..session import SessionError
        if not isinstance(answer, dict):
            raise SessionError("search answer: expected {'choose': k}, {'save': k} or "
                               "{'stop': true}, got %r" % (answer,))
        level = answer.get("level")
        what = [k for k in answer if k != "level"]
        if len(what) != 1 or (level is not None and what[0] == "stop"):
            raise SessionError("search answer: expected {'choose': k}, {'save': k} (with the "
                               "friction slider's 'level') or {'stop': true}, got %r"
                               % (answer,))
        k = answer[what[0]]
        if what[0] == "choose":
            return state.choose(k, level)
        if what[0] == "save":
            return state.save(k, level)
        if what[0] == "stop" and k is True:
            return state.stop()
        raise SessionError("search answer: expected choose, save or stop, got %r" % (answer,))

    def normalise(self, q: Any, state: Any, answer: Any) -> Any:
        """One of the question's answers; a choose or save may carry the
        friction slider's level (checked: in range, and a search with a slider)."""
        if isinstance(answer, dict) and "level" in answer and len(answer) == 2:
            if not state.level_slider:
                raise ValueError("answer: this search has no friction slider: no 'level'")
            check_level(answer["level"])
            rest = {k: v for k, v in answer.items() if k != "level"}
            if "stop" in rest:
                raise ValueError("answer: a stop carries no level")
            super().normalise(q, state, rest)
            return answer
        return super().normalise(q, state, answer)

    def feel_scene(self, state: Any, q: Any, k: int, feel: dict[str, Any]) -> dict[str, Any]:
        """Option k at the friction slider's level (feel["level"]): the
        candidate's texel region with that gain."""
        level = feel.get("level")
        if level is None:
            return q.options[k]
        if not state.level_slider:
            raise ValueError("level: this search has no friction slider")
        g = check_level(level)
        scene = json.loads(json.dumps(q.options[k]))
        scene["regions"][-1]["texture"]["gain"] = g
        return scene

    def feel_state(self, state: Any) -> dict[str, Any]:
        """What a feel starts from for a new question: the slider's level."""
        return {"level": state.level} if state.level_slider else {}

    def resolved(self, state: Any, config: dict[str, Any]) -> dict[str, Any]:
        """Every field the search runs with (its defaults included) and the
        scenes' keys the config gave."""
        out = {k: getattr(state, k) for k in ("dims", "sigma0", "texture_seed", "cma_update",
                                               "level_slider", "level_start")}
        out["x0"] = list(state.x0) if state.x0 is not None else None
        out.update({k: config[k] for k in SCENE_KEYS if k in config})
        return json.loads(json.dumps(out))

    def estimate(self, state: Any) -> dict[str, float]:
        return played_db(Point(state.mean[0], state.mean[1]))

    def simulate(self, who: Any, state: Any) -> Any:
        return {"choose": who.pick(state.ask())}

    def columns(self, state: Any, a: Any) -> dict[str, Any]:
        return dict(chosen=a["choose"], trial=state.iteration) if "choose" in a else {}

    def full_config(self, state: Any, header: dict[str, Any]) -> dict[str, Any]:
        """Its own fields (no Config) and the scenes' keys."""
        fields = {k: getattr(state, k) for k in ("dims", "x0", "sigma0", "texture_seed",
                                                   "texture_format", "cma_update",
                                                   "level_slider", "level_start")}
        fields["x0"] = fields["x0"] if fields["x0"] is not None else [0.5] * len(state.dims)
        out = dict(fields, **{k: v for k, v in header.items() if k in SCENE_KEYS})
        return json.loads(json.dumps(out))


PROTOCOL = SearchProtocol()
