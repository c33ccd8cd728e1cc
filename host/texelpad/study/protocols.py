"""The protocols by name, and resuming a session: a protocol's state is a
pure function of (config, seed, the answers so far), so a session file
rebuilds it exactly - after a crash at any point, or to replay it.

    state = start(protocol, config, seed)
    apply(protocol, state, answer)        # what a participant answered
    state = replay(session)               # texelpad.study.session.Session

Answers: free {"pitch_db", "irregularity_db", "confidence"}; quant a
similarity 1..5; pursuit "A" | "B" | "unsure"; staircase true | false (the odd
one was found); search {"choose": k} | {"save": k} | {"stop": true}; mapping
{"pitch", "irregularity"} (sliders 0..100), then a similarity 0..10.
Every state has `done`.
"""
from __future__ import annotations

import dataclasses
import json
from typing import Any

from ..search.preference import PreferenceSearch
from . import free as _free
from . import mapping as _mapping
from . import pursuit as _pursuit
from . import quant as _quant
from . import scenes as _scenes
from . import staircase as _staircase
from .session import Session, SessionError

PROTOCOLS = ("free", "quant", "pursuit", "staircase", "search", "mapping")
TITLES = {"free": "free exploration (seed 000)",
          "quant": "quantization test (seed 000)",
          "pursuit": "guided exploration: pursuit vector (seed 000)",
          "staircase": "texel-length oddity staircase (seed 001)",
          "search": "preference-driven search: CMA-ES (seed 003)",
          "mapping": "texel parameter mapping (seed 001, second experiment)"}
# config keys that are not the state's: the scenes' business (the texture
# compared against, the staircase's texel texture, the texel textures' format)
# and the config file's name
SCENE_KEYS = ("reference", "distribution", "texture_format", "config_file")


def start(protocol: str, config: dict[str, Any], seed: int) -> Any:
    """The protocol's state before any answer. config: its Config's fields
    (JSON); "reference" (the texture compared against: the scenes' business)
    and "distribution" (the staircase's texel texture) are not the state's,
    nor "texture_format" (1 or 2, default 2: checked here, played by scenes)."""
    fmt = _scenes.texture_format(config)
    config = {k: v for k, v in config.items() if k not in SCENE_KEYS}
    if protocol == "free":
        return _free.Free(seed, _free.Config(**_tuples(config)))
    if protocol == "quant":
        return _quant.Quant(seed, _quant.Config(**_tuples(config)))
    if protocol == "pursuit":
        return _pursuit.Pursuit(seed, _pursuit.Config(**_tuples(config)))
    if protocol == "staircase":
        return _staircase.Staircase(_staircase.Config(**config))
    if protocol == "search":
        return PreferenceSearch(seed, texture_format=fmt, **_tuples(config))
    if protocol == "mapping":
        return _mapping.Mapping(seed, _mapping.Config(**_tuples(config)))
    raise SessionError("protocol: unknown %r (known: %s)" % (protocol, ", ".join(PROTOCOLS)))


def resolved(protocol: str, state: Any, config: dict[str, Any]) -> dict[str, Any]:
    """The config a session's header records: every field of the protocol's
    Config as it runs (the defaults it filled in included, so the header
    names every choice the paper leaves open), plus the scenes' keys the
    config gave (SCENE_KEYS). The search keeps what it was given."""
    cfg = getattr(state, "config", None)
    if protocol == "search" or not dataclasses.is_dataclass(cfg) or isinstance(cfg, type):
        return dict(config)
    out = json.loads(json.dumps(dataclasses.asdict(cfg)))
    out.update({k: config[k] for k in SCENE_KEYS if k in config})
    return out


def _tuples(config: dict[str, Any]) -> dict[str, Any]:
    # JSON has lists where the configs hold tuples
    return {k: tuple(v) if isinstance(v, list) else v for k, v in config.items()}


def apply(protocol: str, state: Any, answer: Any) -> dict:
    if protocol in ("free", "quant", "pursuit", "staircase", "mapping"):
        return state.answer(answer)
    if protocol == "search":
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
    raise SessionError("protocol: unknown %r" % (protocol,))


def done(state: Any) -> bool:
    return bool(state.done)


def replay(session: Session) -> Any:
    """The protocol state after every answer the session file holds."""
    h = session.header
    state = start(h["protocol"], h["config"], h["seed"])
    for rec in session.answers():
        apply(h["protocol"], state, rec["answer"])
    return state
