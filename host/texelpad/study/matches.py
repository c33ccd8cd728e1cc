"""A participant's own matches, from their finished sessions, for the
quantization test and the similarity matrix (study/quant.py): pure logic on
session files (study/session.py), used by the lab's server for matches_from.

- A free exploration gives, per reference, the texture that PLAYED when the
  participant submitted the match: the texel texture of that answer record's
  scene (its parameters, seed, texel length and format), so the quantization
  test renders the very pitch sequence that was felt (seed 000).
- A finished guided exploration gives its end point, a stopped search its
  mean, for the reference it ran on (no seed: nothing was felt at that point).
"""
from __future__ import annotations

from typing import Any

from . import protocols
from . import questions as Q
from .session import Session

FELT_KEYS = ("pitch_db", "irregularity_db", "seed", "texel_samples", "v")


def _texel_of(scene: Any) -> dict[str, Any] | None:
    regs = scene.get("regions") if isinstance(scene, dict) else None
    for r in reversed(regs or []):
        t = r.get("texture") if isinstance(r, dict) else None
        if isinstance(t, dict) and t.get("kind") == "texel":
            return t
    return None


def from_free(session: Session, state: Any) -> dict[str, dict[str, Any]]:
    """{reference: the texture felt when the match was submitted}: from the
    answer record's scene; a record without one (a file from before scenes
    were recorded) gives the match's parameters alone."""
    out: dict[str, dict[str, Any]] = {}
    records = list(session.answers())
    for k, m in enumerate(state.matches):
        felt = _texel_of(records[k].get("scene")) if k < len(records) else None
        if felt is not None and all(key in felt for key in FELT_KEYS):
            out[m["reference"]] = {key: felt[key] for key in FELT_KEYS}
        else:
            out[m["reference"]] = {"pitch_db": m["pitch_db"],
                                   "irregularity_db": m["irregularity_db"]}
    return out


def from_end_point(protocol: str, session: Session, state: Any) -> dict[str, dict[str, Any]]:
    """{the reference it ran on: its end point} of a finished guided
    exploration or a stopped search (ValueError says why not)."""
    sid = session.path.stem
    if protocols.get(protocol).GIVES_MATCHES != "end point":
        raise ValueError("matches_from: %s is a %s session: matches come from a free "
                         "exploration, a guided exploration or a search" % (sid, protocol))
    if not state.done:
        raise ValueError("matches_from: %s is not finished" % sid)
    ref = session.header["config"].get("reference") or {}
    if ref.get("kind") != "reference":
        raise ValueError("matches_from: %s did not run on a reference texture" % sid)
    point = Q.estimate(protocol, state)
    return {ref["name"]: {"pitch_db": point["pitch_db"],
                          "irregularity_db": point["irregularity_db"]}}


def from_session(protocol: str, session: Session, state: Any) -> dict[str, dict[str, Any]]:
    """The matches a session gives (its protocol's GIVES_MATCHES: a free
    exploration's, or the end point of a guided exploration or a search);
    ValueError says why not."""
    if protocols.get(protocol).GIVES_MATCHES == "matches":
        return from_free(session, state)
    return from_end_point(protocol, session, state)


def references_of(config: dict[str, Any]) -> tuple[str, ...]:
    """The references a quant config rates (its Config's default when it
    names none): the config's own resolution, its matches aside (they are
    what is being looked for). ValueError for a config the protocol refuses."""
    return tuple(protocols.start("quant", dict(config, matches=None), 0).config.references)


def from_saved(session: Session, state: Any) -> dict[str, Any]:
    """Seed 003's Phase 2 input: the texture a stopped search saved last, for
    the reference it ran on ({name, reference, texture}); ValueError says why not."""
    sid = "%s/%s" % (session.header.get("participant"), session.path.stem)
    proto = session.header.get("protocol")
    if not protocols.get(proto).GIVES_SAVED:
        raise ValueError("matches_from: %s is a %s session: the evaluation rates stopped "
                         "searches' saved textures" % (sid, proto))
    if not state.done:
        raise ValueError("matches_from: %s is not stopped" % sid)
    if not state.saved:
        raise ValueError("matches_from: %s saved no texture" % sid)
    ref = session.header["config"].get("reference") or {}
    if ref.get("kind") != "reference":
        raise ValueError("matches_from: %s did not run on a reference texture" % sid)
    return {"name": "VTp %s" % sid, "reference": ref["name"],
            "texture": dict(state.saved[-1]["params"])}
