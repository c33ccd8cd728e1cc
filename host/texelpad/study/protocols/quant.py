"""The quantization test (seed 000; design "matrix": the similarity matrix):
the participant rates how similar the reference and a rendering of a match
feel. Its state: study/quant.py."""
from __future__ import annotations

from typing import Any

from .. import quant as QT
from .. import rater
from .. import scenes as S
from ..describing import split, whole
from ..free import rating_input
from ..question import Question, format_of
from .base import Protocol, tuples


def _ask(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    if st.done:
        return Question({"done": True}, detail={"ratings": st.ratings})
    ref, level = st.current
    tex = st.texture(format_of(header))
    shown = tex if tex.get("kind") != "samples" else {   # (9,600 values: the record has them)
        "kind": "samples", "rater": st.current_match, "quant_db": level,
        "texel_samples": rater.texel_samples(), "values": len(tex["u16"])}
    rating = rating_input(st.config.scale, st.config.rating)   # (the app's: a slider from 3)
    reference = {"kind": "reference", "name": ref}
    if st.config.presentation == "whole":   # the guided app's: one at a time, whole display
        names = ["reference", "rendering"]
        scenes = [S.whole(reference, display, name="reference"),
                  S.whole(tex, display, name="rendering")]
    else:
        names = ["rendering"]
        scenes = [S.split(reference, tex, display, name="rendering")]
    return Question(dict({"done": False, "kind": "rate", "trial": st.trial,
                          "of": len(st.trials), "options": names,
                          "presentation": st.config.presentation}, **rating),
                    scenes,
                    {"reference": ref, "match_of": st.current_match, "source": st.current_source,
                     "quant_db": level, "texture": shown, "match_source": st.config.match_source})


def _trials(st: Any, header: dict[str, Any], display: dict[str, Any],
            listed: int = 0) -> dict[str, Any]:
    c = st.config
    v = format_of(header)
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
        if c.presentation == "whole":
            options = [whole("reference", left, display), whole("rendering", right, display)]
        else:
            options = [split("rendering", left, right, display)]
        trials.append({"trial": k, "reference": ref, "match_of": of, "source": src,
                       "quant_db": q, "options": options,
                       "answer": "similarity %d .. %d" % tuple(c.scale)})
    rules = ["design %r, order %r: the trial order is drawn from the session's seed"
             % (c.design, c.order) if c.order == "seeded" else
             "design 'matrix', order 'lab': the guided app's fixed ratingorder" if
             c.design == "matrix" else
             "design %r, order 'lab': the app's fixed compareOrder" % c.design]
    rules.append("presentation %r: %s" % (c.presentation, "the reference and the rendering one "
                 "at a time on the whole display" if c.presentation == "whole" else
                 "the reference on the left half, the rendering on the right"))
    if c.matches is None:
        rules.append("no matches in the config: the lab starts it with matches_from (the "
                     "participant's free exploration); each own trial plays the texture felt "
                     "when that match was submitted")
    return {"trials": trials, "rules": rules}


def _plot(fig: Any, ax: Any, state: Any) -> None:
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


class QuantProtocol(Protocol):
    NAME = "quant"
    TITLE = "quantization test (seed 000)"
    TAKES_MATCHES = True
    FIXED = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return QT.Quant(seed, QT.Config(**tuples(config)))

    def normalise(self, q: Question, state: Any, answer: Any) -> Any:
        return state.checked_answer(answer)

    def simulate(self, who: Any, state: Any) -> Any:
        return who.rate(state)

    def columns(self, state: Any, a: Any) -> dict[str, Any]:
        ref, level = state.current
        return dict(similarity=a, quant_db=level, reference=ref, trial=state.trial,
                    match_of=state.current_match, source=state.current_source)


PROTOCOL = QuantProtocol()
