"""The free exploration (seed 000): the participant sets two sliders until the
right half feels like the reference on the left, for each of the nine
references in turn, with a confidence. Its state: study/free.py."""
from __future__ import annotations

from typing import Any

from .. import free as F
from ..describing import option
from ..question import Question, slider_scene
from ..space import irregularity_db, pitch_db
from .base import Protocol, tuples


def _ask(st: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
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


def _trials(st: Any, header: dict[str, Any], display: dict[str, Any],
            listed: int = 0) -> dict[str, Any]:
    c = st.config
    trials = []
    while not st.done:
        sc, _ = slider_scene(st, header, display, c.start[0], c.start[1], 0)
        trials.append({"trial": st.trial, "reference": st.reference,
                       "options": [option("sliders", sc, display)], "move": 0,
                       "answer": "pitch_db, irregularity_db (sliders), confidence %d .. %d"
                                 % tuple(c.confidence)})
        st.answer({"pitch_db": c.start[0], "irregularity_db": c.start[1],
                   "confidence": c.confidence[0]})
    return {"trials": trials, "rules": [
        "every slider change re-draws the rendering with a fresh texture seed drawn from "
        "(session seed, trial, move) (study/free.py Free.texture); move 0 is listed",
        "the sliders start at pitch %g dB, irregularity %g dB (%s slider)"
        % (c.start[0], c.start[1], c.irregularity_slider)]}


def _plot(fig: Any, ax: Any, state: Any) -> None:
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


class FreeProtocol(Protocol):
    NAME = "free"
    TITLE = "free exploration (seed 000)"
    SLIDER_KEYS = ("pitch_db", "irregularity_db")
    GIVES_MATCHES = "matches"
    FIXED = True
    ON_PLANE = True

    ask = staticmethod(_ask)
    plot = staticmethod(_plot)
    trials = staticmethod(_trials)

    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        return F.Free(seed, F.Config(**tuples(config)))

    def normalise(self, q: Question, state: Any, answer: Any) -> Any:
        return state.checked_answer(answer)

    def simulate(self, who: Any, state: Any) -> Any:
        """Its sliders on the target, plus the noise, with confidence 4."""
        c = state.config
        p = min(c.pitch_db[1], max(c.pitch_db[0], pitch_db(who.target.u + who.jitter(1.0))))
        s = min(c.irregularity_db[1], max(c.irregularity_db[0],
                                           irregularity_db(who.target.v + who.jitter(1.0))))
        return {"pitch_db": round(p, 3), "irregularity_db": round(s, 3), "confidence": 4}

    def columns(self, state: Any, a: Any) -> dict[str, Any]:
        return dict(match_pitch_db=a["pitch_db"], match_irregularity_db=a["irregularity_db"],
                    confidence=a["confidence"], reference=state.reference, trial=state.trial)


PROTOCOL = FreeProtocol()
