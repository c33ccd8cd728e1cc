"""What a protocol asks now, as the lab shows it: the participant's view (blind:
option labels and the allowed answers, never a parameter value), the scenes
the options play, and the experimenter's view (the parameters, the state).
Built from the protocol's state, the session's header and the board's display;
pure logic (scenes are plain dicts for Board.push; the web layer pushes them).
Each protocol asks its own (texelpad.study.protocols: one module each); this
module is where the lab asks it.

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

from typing import Any

from . import protocols
from .question import Question, format_of, reference_of, slider_scene

__all__ = ["Question", "SLIDER_KEYS", "ask", "estimate", "format_of", "normalise",
           "reference_of", "slider_scene", "sliding"]

# the two slider values a sliding protocol takes (feel and answer bodies, move records)
SLIDER_KEYS = {n: keys for n in protocols.NAMES
               if (keys := protocols.get(n).SLIDER_KEYS) is not None}


def sliding(protocol: str, state: Any) -> bool:
    """Whether the protocol's current question is answered with sliders."""
    return protocols.get(protocol).sliding(state)


def ask(protocol: str, state: Any, header: dict[str, Any], display: dict[str, Any]) -> Question:
    return protocols.get(protocol).ask(state, header, display)


def estimate(protocol: str, st: Any) -> dict[str, float]:
    """Where a guided exploration (its centre) or a search (its mean) ended,
    in dB (clamped to what the display plays: texelpad.study.space)."""
    return protocols.get(protocol).estimate(st)


def normalise(protocol: str, q: Question, state: Any, answer: Any) -> Any:
    """The answer as the protocol takes it, checked against the question
    (ValueError says why; nothing has changed). Answers are compared as JSON,
    so true is not 1 and {"choose": true} is not {"choose": 1}."""
    if q.done:
        raise ValueError("the session is finished")
    return protocols.get(protocol).normalise(q, state, answer)
