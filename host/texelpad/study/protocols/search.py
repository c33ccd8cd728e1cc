"""The preference-driven search (seed 003): CMA-ES over the texel space, the
participant picking the closest of three candidates (or saving one, or
stopping). Its state: texelpad.search.preference.PreferenceSearch."""
from __future__ import annotations

import json
import math
from typing import Any

from ...search.preference import PreferenceSearch, candidate_params
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
        "mirrored, sigma0 %g); the participant stops when satisfied" % st.sigma0]}


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
    ON_PLANE = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return PreferenceSearch(seed, texture_format=fmt, **tuples(config))

    def apply(self, state: Any, answer: Any) -> dict[str, Any]:
        from ..session import SessionError
        if not isinstance(answer, dict) or len(answer) != 1:
            raise SessionError("search answer: expected {'choose': k}, {'save': k} or "
                               "{'stop': true}, got %r" % (answer,))
        (what, k), = answer.items()
        if what == "choose":
            return state.choose(k)
        if what == "save":
            return state.save(k)
        if what == "stop" and k is True:
            return state.stop()
        raise SessionError("search answer: expected choose, save or stop, got %r" % (answer,))

    def resolved(self, state: Any, config: dict[str, Any]) -> dict[str, Any]:
        return dict(config)             # (no Config: it keeps what it was given)

    def estimate(self, state: Any) -> dict[str, float]:
        return played_db(Point(state.mean[0], state.mean[1]))

    def simulate(self, who: Any, state: Any) -> Any:
        return {"choose": who.pick(state.ask())}

    def columns(self, state: Any, a: Any) -> dict[str, Any]:
        return dict(chosen=a["choose"], trial=state.iteration) if "choose" in a else {}

    def full_config(self, state: Any, header: dict[str, Any]) -> dict[str, Any]:
        """Its own fields (no Config) and the scenes' keys."""
        fields = {k: getattr(state, k) for k in ("dims", "x0", "sigma0", "texture_seed",
                                                   "texture_format")}
        fields["x0"] = fields["x0"] if fields["x0"] is not None else [0.5] * len(state.dims)
        out = dict(fields, **{k: v for k, v in header.items() if k in SCENE_KEYS})
        return json.loads(json.dumps(out))


PROTOCOL = SearchProtocol()
