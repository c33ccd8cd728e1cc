"""What a study protocol is to the rest of texelpad: one subclass per protocol
(a module of this package; the registry: __init__.py), holding everything the
lab's server, `texelpad lab export`, `texelpad lab describe` and the simulated
participant ask of it - so a new protocol is a new module here and its tests
(docs/architecture.md, "a new protocol").

A protocol's *state* (study/free.py Free, study/pursuit.py Pursuit, ...) is a
pure function of (config, seed, the answers so far); this class is what
turns it into questions, scenes, rows and figures. Pure logic: no link, no web.
"""
from __future__ import annotations

import dataclasses
import json
from typing import Any

from ..question import Question, js

# config keys that are not the state's: the scenes' business (the texture
# compared against, the staircase's texel texture, the texel textures' format)
# and the config file's name
SCENE_KEYS = ("reference", "distribution", "texture_format", "config_file")


def tuples(config: dict[str, Any]) -> dict[str, Any]:
    """JSON has lists where the configs hold tuples."""
    return {k: tuple(v) if isinstance(v, list) else v for k, v in config.items()}


class Protocol:
    NAME = ""
    TITLE = ""
    # the two values it asks with sliders (feel and answer bodies, move records)
    SLIDER_KEYS: tuple[str, str] | None = None
    # the texture compared against is the session's (the experimenter's pick;
    # 4sin by default: scenes.DEFAULT_REFERENCE); the others name theirs in the config
    REFERENCE_CHOSEN = False
    # it rates the participant's own matches: started with matches_from (web/server.py)
    TAKES_MATCHES = False
    # it rates stopped searches' saved textures: started with matches_from (web/server.py)
    TAKES_SAVED = False
    # a stopped session of it gives a TAKES_SAVED protocol its saved texture (matches.py)
    GIVES_SAVED = False
    # what a finished session of it gives a TAKES_MATCHES protocol (study/matches.py):
    # "matches" (one per reference) or "end point" (the one it ran on); None: nothing
    GIVES_MATCHES: str | None = None
    # its trial list is fixed by the config and seed (describe: listed exactly);
    # otherwise the answers steer it (adaptive: the first question and the rules)
    FIXED = False
    # its session figure shows the nine references on the pitch-irregularity plane
    ON_PLANE = False
    # the lab records the board's telemetry per trial in its sessions (study/finger.py)
    # at its Config's finger_hz samples per second
    RECORDS_FINGER = False

    # --- the state ----------------------------------------------------------------------
    def state(self, config: dict[str, Any], seed: int, fmt: int) -> Any:
        """The state before any answer (config: its Config's fields, as JSON
        with lists made tuples; fmt: the texel textures' format)."""
        raise NotImplementedError

    def apply(self, state: Any, answer: Any) -> dict[str, Any]:
        """The state after an answer (a checked one: normalise); what it did."""
        return state.answer(answer)

    def resolved(self, state: Any, config: dict[str, Any]) -> dict[str, Any]:
        """The config a session's header records: every field of the
        protocol's Config as it runs (the defaults it filled in included, so
        the header names every choice the paper leaves open), plus the
        scenes' keys the config gave (SCENE_KEYS)."""
        out = json.loads(json.dumps(dataclasses.asdict(state.config)))
        out.update({k: config[k] for k in SCENE_KEYS if k in config})
        return out

    # --- asking (study/questions.py) ------------------------------------------------------
    # (ask, plot and trials: a module's functions, staticmethod(_ask) ...; positional only)
    def ask(self, state: Any, header: dict[str, Any], display: dict[str, Any], /) -> Question:
        """What it asks now: the participant's view, the scenes, the
        experimenter's view (study/questions.py)."""
        raise NotImplementedError

    def sliding(self, state: Any) -> bool:
        """Whether the question asked now is answered with sliders."""
        return self.SLIDER_KEYS is not None

    def normalise(self, q: Question, state: Any, answer: Any) -> Any:
        """The answer as apply takes it, or ValueError (nothing changed). By
        default one of the question's answers, compared as JSON (true is not 1)."""
        allowed = q.public["answers"]
        if js(answer) not in [js(a) for a in allowed]:
            raise ValueError("answer: expected one of %s, got %s" % (js(allowed), js(answer)))
        return answer

    # keys a feel request may carry besides its option (the search's friction slider)
    FEEL_KEYS: tuple[str, ...] = ()

    def feel_scene(self, state: Any, q: Question, k: int, feel: dict[str, Any]
                   ) -> dict[str, Any]:
        """The scene option k plays with the feel's FEEL_KEYS settings."""
        return q.options[k]

    def feel_state(self, state: Any) -> dict[str, Any]:
        """The FEEL_KEYS settings a new question starts from."""
        return {}

    def record(self, q: Question, answer: Any) -> dict[str, Any]:
        """What the session file keeps beside an answer, besides the question,
        the answer taken, the scene and the state (the server's record)."""
        return {}

    def result_shown(self, result: dict[str, Any]) -> dict[str, Any] | None:
        """What the participant's page is told an answer did."""
        return result

    def estimate(self, state: Any) -> dict[str, float]:
        """Where it ended, in dB (an end point: GIVES_MATCHES "end point")."""
        raise ValueError("estimate: %r has no end point" % (self.NAME,))

    # --- the simulated participant (study/participant.py) --------------------------------
    def simulate(self, who: Any, state: Any) -> Any:
        """The simulated participant `who`'s answer to the question asked now."""
        raise NotImplementedError

    def finger_hz(self, state: Any) -> int:
        """Telemetry samples per second the lab records per trial (0: none)."""
        return int(getattr(state.config, "finger_hz", 0)) if self.RECORDS_FINGER else 0

    # --- export (study/export.py) ---------------------------------------------------------
    def columns(self, state: Any, answer: Any) -> dict[str, Any]:
        """The export row's columns of an answer's kind, from the state before it."""
        return {}

    def columns_after(self, result: dict[str, Any]) -> dict[str, Any]:
        """Columns only the answer's result knows (the state after it)."""
        return {}

    def plot(self, fig: Any, ax: Any, state: Any, /) -> None:
        """The session's summary figure, on matplotlib's fig and ax."""

    # --- describe (study/describe.py) -----------------------------------------------------
    def full_config(self, state: Any, header: dict[str, Any]) -> dict[str, Any]:
        """Every choice field, as `texelpad lab describe` lists it."""
        return self.resolved(state, header)

    def trials(self, state: Any, header: dict[str, Any], display: dict[str, Any],
               listed: int, /) -> dict[str, Any]:
        """{"trials": [...], "rules": [...]}: the trial list before anyone
        runs it (listed: how many an open-ended one lists)."""
        raise NotImplementedError
