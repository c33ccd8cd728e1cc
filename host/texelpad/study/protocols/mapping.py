"""Seed 001's second experiment, the texel parameter mapping: two plain
sliders matched to each band-pass reference, then the matches rated against
the references. Its state: study/mapping.py."""
from __future__ import annotations

from typing import Any

from .. import bandpass
from .. import mapping as MP
from ..mapping import SLIDER
from .. import scenes as S
from ..describing import option, split
from ..question import Question, format_of, slider_scene
from .base import Protocol, tuples


def _ask(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
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


def _trials(st: Any, header: dict[str, Any], display: dict[str, Any],
            listed: int = 0) -> dict[str, Any]:
    c = st.config
    trials = []
    while st.phase == "match":
        ref = st.reference
        sc, _ = slider_scene(st, header, display, c.start[0], c.start[1], 0)
        what = "band-pass reference %s seed %d" % (ref, c.reference_seed)
        trials.append({"trial": st.trial, "phase": "match", "reference": ref,
                       "options": [option("sliders", sc, display, what)], "move": 0,
                       "answer": "pitch, irregularity (sliders 0 .. 100)"})
        st.answer({"pitch": c.start[0], "irregularity": c.start[1]})
    for k, (ref, of) in enumerate(st.pairs):
        left = bandpass.board_texture(ref) if c.reference_play == "board" else {
            "kind": "samples", "fit": "tile", "values": bandpass.HALF_SCREEN,
            "what": "band-pass reference %s seed %d" % (ref, c.reference_seed)}
        right = {"kind": "texel", "what": "the participant's own match of %s (from phase 1)"
                 % of, "texel_samples": c.texel_samples, "seed": st.rating_seeds[of],
                 "min_cpmm": c.min_cpmm, "phase": c.phase, "v": format_of(header)}
        trials.append({"trial": k, "phase": "rate", "reference": ref, "match_of": of,
                       "options": [split("rendering", left, right, display)],
                       "answer": "similarity %d .. %d" % tuple(c.scale)})
    return {"trials": trials, "rules": [
        "phase 1: every slider change re-draws with a fresh seed from (session seed, trial, "
        "move); move 0 (the sliders' start) is listed",
        "phase 2 plays each participant's phase-1 match with the seed listed (one per match)"]}


def _plot(fig: Any, ax: Any, state: Any) -> None:
    """The mapping's matches: the chosen mean pitch (c/mm) against the
    reference's central frequency, per zeta, with the diagonal (Fig. 4a)."""
    from ..mapping import summary
    sm = summary(state)
    for k, row in enumerate(sm["fig4a"]):
        pts = [(f, m) for f, m in zip(row["fc_cpmm"], row["mean_cpmm"]) if m is not None]
        if pts:
            ax.plot([f * 1.06 ** (k - 1) for f, _ in pts], [m for _, m in pts], "o",
                    color="C%d" % k, label="zeta %g" % row["zeta"])
    ax.plot([0.5, 40], [0.5, 40], ":", color="0.5")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("reference central frequency (c/mm)")
    ax.set_ylabel("chosen pitch: the lognormal's mean (c/mm)")
    rated = len(state.ratings)
    ax.text(0.01, 0.99, "%d matches, %d ratings%s" % (
        len(state.matches), rated, "; self-match mean %.2f" % sm["self"]["mean"]
        if sm["self"]["n"] else ""), transform=ax.transAxes, va="top", fontsize=7)
    if state.matches:
        ax.legend(fontsize=8)


class MappingProtocol(Protocol):
    NAME = "mapping"
    TITLE = "texel parameter mapping (seed 001, second experiment)"
    SLIDER_KEYS = ("pitch", "irregularity")
    FIXED = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return MP.Mapping(seed, MP.Config(**tuples(config)))

    def sliding(self, state: Any) -> bool:
        return state.phase == "match"           # then the ratings: buttons

    def normalise(self, q: Question, state: Any, answer: Any) -> Any:
        return state.checked_answer(answer)

    def simulate(self, who: Any, state: Any) -> Any:
        return who.map_answer(state)

    def columns(self, state: Any, a: Any) -> dict[str, Any]:
        if state.phase == "match":
            return dict(reference=state.reference, trial=state.trial, pitch_slider=a["pitch"],
                        irregularity_slider=a["irregularity"])
        ref, of = state.current             # a rating: the match of match_of played
        m = state.match_of(of) or {}
        return dict(reference=ref, match_of=of, similarity=a, trial=state.trial,
                    pitch_slider=m.get("pitch", ""), irregularity_slider=m.get("irregularity", ""),
                    match_pitch_db=m.get("pitch_db", ""),
                    match_irregularity_db=m.get("irregularity_db", ""))

    def columns_after(self, result: dict[str, Any]) -> dict[str, Any]:
        if "similarity" in result:
            return {}
        return dict(match_pitch_db=result["pitch_db"],          # a match: its dB as played
                    match_irregularity_db=result["irregularity_db"])


PROTOCOL = MappingProtocol()
