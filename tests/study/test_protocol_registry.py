"""The study protocols' registry (host/texelpad/study/protocols/): the names
and the modules agree, every module's PROTOCOL is a base.Protocol that
holds what the lab, export, describe and the simulated participant ask of it
(each protocol run to its end through the registry alone), no host file
outside the registry decides by a protocol's name what the protocol knows,
and docs/architecture.md's list of files for a new protocol is true."""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

from texelpad.study import protocols as P
from texelpad.study import questions as Q
from texelpad.study.participant import SimulatedParticipant
from texelpad.study.protocols.base import Protocol
from texelpad.study.session import SessionError
from texelpad.study.space import Point

ROOT = Path(__file__).resolve().parents[2]
DIR = ROOT / "host" / "texelpad" / "study" / "protocols"
DISPLAY = {"positions": 19200, "dx_um": 5.3}
# the smallest config each protocol runs with (the quantization test rates matches)
CONFIGS = {"quant": {"matches": {r: {"pitch_db": 5.0, "irregularity_db": -10.0}
                                 for r in ("4sin", "pink", "sawtooth")},
                     "design": "levels", "texel_samples": 50}}
HEADER_CONFIG = {"pursuit": {"reference": {"kind": "reference", "name": "4sin"}},
                 "search": {"reference": {"kind": "reference", "name": "4sin"}}}


def test_the_names_are_the_modules():
    mods = sorted(p.stem for p in DIR.glob("*.py") if p.stem not in ("__init__", "base"))
    assert sorted(P.NAMES) == mods
    assert P.PROTOCOLS == P.NAMES and set(P.TITLES) == set(P.NAMES)


@pytest.mark.parametrize("name", P.NAMES)
def test_every_protocol_is_one(name):
    p = P.get(name)
    assert isinstance(p, Protocol) and p.NAME == name and p.TITLE
    overridden = {k for k in ("state", "ask", "simulate", "trials")
                  if getattr(type(p), k) is not getattr(Protocol, k)}
    assert overridden == {"state", "ask", "simulate", "trials"}, name
    assert p.GIVES_MATCHES in (None, "matches", "end point")
    assert (name in Q.SLIDER_KEYS) == (p.SLIDER_KEYS is not None)


def test_an_unknown_protocol_names_the_known_ones():
    with pytest.raises(SessionError, match=r"protocol: unknown 'chirp' \(known: free, quant"):
        P.get("chirp")
    with pytest.raises(SessionError, match="unknown"):
        P.start("chirp", {}, 0)


@pytest.mark.parametrize("name", P.NAMES)
def test_every_protocol_runs_to_its_end_through_the_registry(name):
    """Ask, check the simulated answer, apply, export its columns - as the
    lab's server and `texelpad lab export` do - until it is done."""
    p = P.get(name)
    config = dict(CONFIGS.get(name, {}))
    if name == "staircase":
        config["stop_after_reversals"] = 4
    state = P.start(name, config, 3)
    header = {"protocol": name, "seed": 3, "config": dict(config, **HEADER_CONFIG.get(name, {}))}
    who = SimulatedParticipant(Point(0.6, 0.4), noise=0.02, seed=1, feel="plane",
                               threshold_mm=2.0)
    for n in range(400):
        q = Q.ask(name, state, header, DISPLAY)
        if q.done or (name == "search" and n == 12):
            break
        a = who.answer(name, state)
        if Q.sliding(name, state):
            assert q.public["kind"] == "sliders"
        else:
            # the page sends what it was offered (the staircase: the option picked)
            a = ([0, 1, 2][q.odd if a else (q.odd + 1) % 3] if name == "staircase" else a)
        taken = Q.normalise(name, q, state, a)
        p.columns(state, taken)
        p.columns_after(P.apply(name, state, taken))
        p.record(q, a)
    if name != "search":
        assert state.done, name
    d = p.full_config(state, header["config"])
    assert isinstance(d, dict)


# --- no protocol-by-name decisions outside the registry -----------------------------------
# The papers' figures over all sessions (export.py figN_data) take the sessions of the
# protocol each paper's figure is about (a lookup by name, not a decision), and a
# config names its protocol. study/legacy.py is the history of the session file format:
# what older texelpads wrote for the protocols they had, frozen (a new protocol has none).
ALLOWED = ("host/texelpad/study/legacy.py",)
def _decisions(path: Path) -> list[str]:
    """`x == "free"`, `x in ("pursuit", "search")`, ...: a comparison with a
    protocol's name."""
    out = []
    tree = ast.parse(path.read_text())
    for n in ast.walk(tree):
        if not isinstance(n, ast.Compare):
            continue
        consts = []
        for c in [n.left] + list(n.comparators):
            if isinstance(c, ast.Constant):
                consts.append(c.value)
            elif isinstance(c, (ast.Tuple, ast.List, ast.Set)):
                consts += [e.value for e in c.elts if isinstance(e, ast.Constant)]
        names = [c for c in consts if c in P.NAMES and c not in ("free",)] + \
            [c for c in consts if c == "free" and any(k in P.NAMES for k in consts if k != c)]
        if names or "free" in consts and _is_protocol(n):
            out.append("%s:%d" % (path.relative_to(ROOT), n.lineno))
    return out


def _is_protocol(n: ast.Compare) -> bool:
    """A comparison of "free" with something named like a protocol."""
    text = ast.unparse(n)
    return bool(re.search(r"proto", text))


def test_no_protocol_by_protocol_decisions_outside_the_registry():
    files = [p for p in (ROOT / "host" / "texelpad").rglob("*.py") if DIR not in p.parents]
    found = [d for p in files for d in _decisions(p) if not d.startswith(ALLOWED)]
    assert found == [], found


def test_the_architecture_doc_lists_the_files_of_a_new_protocol():
    doc = (ROOT / "docs" / "architecture.md").read_text()
    m = re.search(r"- A new study protocol:(.*?)\n- ", doc, re.S)
    assert m, "docs/architecture.md: no 'A new study protocol' entry"
    entry = m.group(1)
    for must in ("host/texelpad/study/protocols/<name>.py", "protocols.NAMES",
                 "host/texelpad/study/protocols/base.py", "tests/study/"):
        assert must in entry, must
    for p in re.findall(r"`((?:device|host|tests|tools|docs)/[^`<>]+)`", entry):
        assert (ROOT / p).exists(), p
    for p in re.findall(r"`(study/[a-z_]+\.py|web/[a-z_]+\.py)`", entry):
        assert (ROOT / "host" / "texelpad" / p).exists(), p
