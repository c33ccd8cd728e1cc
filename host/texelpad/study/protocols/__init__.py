"""The protocols by name, and resuming a session: a protocol's state is a
pure function of (config, seed, the answers so far), so a session file
rebuilds it exactly - after a crash at any point, or to replay it.

    state = start(protocol, config, seed)
    apply(protocol, state, answer)        # what a participant answered
    state = replay(session)               # texelpad.study.session.Session
    get(protocol)                         # its Protocol (base.py): questions,
                                          # export, figure, describe, simulation

One module per protocol in this folder, each with PROTOCOL, an instance of
its base.Protocol subclass; NAMES lists them (the lab's order). Answers: free
{"pitch_db", "irregularity_db", "confidence"}; quant a similarity 1..5;
pursuit "A" | "B" | "unsure"; staircase true | false (the odd one was found);
search {"choose": k} | {"save": k} (with the friction slider's "level") |
{"stop": true}; mapping {"pitch", "irregularity"} (sliders 0..100), then a
similarity 0..10; evaluate a rating on its scale (an adjective, or a
similarity). Every state has
`done`.
"""
from __future__ import annotations

import importlib
from typing import Any

from .. import scenes as _scenes
from ..session import Session, SessionError
from .base import SCENE_KEYS, Protocol, tuples as _tuples

NAMES = ("free", "quant", "pursuit", "staircase", "search", "mapping", "evaluate")
PROTOCOLS = NAMES
_BY_NAME: dict[str, Protocol] = {
    n: importlib.import_module("%s.%s" % (__name__, n)).PROTOCOL for n in NAMES}
TITLES = {n: p.TITLE for n, p in _BY_NAME.items()}

__all__ = ["NAMES", "PROTOCOLS", "TITLES", "SCENE_KEYS", "Protocol", "get", "start",
           "resolved", "apply", "done", "replay", "_tuples"]


def get(protocol: Any) -> Protocol:
    """The protocol named, or SessionError naming the known ones."""
    p = _BY_NAME.get(protocol) if isinstance(protocol, str) else None
    if p is None:
        raise SessionError("protocol: unknown %r (known: %s)" % (protocol, ", ".join(NAMES)))
    return p


def start(protocol: str, config: dict[str, Any], seed: int) -> Any:
    """The protocol's state before any answer. config: its Config's fields
    (JSON); "reference" (the texture compared against: the scenes' business)
    and "distribution" (the staircase's texel texture) are not the state's,
    nor "texture_format" (1 or 2, default 2: checked here, played by scenes)."""
    p = get(protocol)
    fmt = _scenes.texture_format(config)
    return p.state({k: v for k, v in config.items() if k not in SCENE_KEYS}, seed, fmt)


def resolved(protocol: str, state: Any, config: dict[str, Any]) -> dict[str, Any]:
    """The config a session's header records (base.Protocol.resolved)."""
    return get(protocol).resolved(state, config)


def apply(protocol: str, state: Any, answer: Any) -> dict:
    return get(protocol).apply(state, answer)


def done(state: Any) -> bool:
    return bool(state.done)


def replay(session: Session) -> Any:
    """The protocol state after every answer the session file holds."""
    h = session.header
    state = start(h["protocol"], h["config"], h["seed"])
    for rec in session.answers():
        apply(h["protocol"], state, rec["answer"])
    return state
