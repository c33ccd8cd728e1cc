"""What the fuzz targets share (docs/testing.md, "The nightly fuzz job").

Size and randomness - TEXELPAD_FUZZ:
  unset / "smoke"   SMOKE_CASES (50) cases per target, derandomized unless
                    TEXELPAD_HYPOTHESIS=nightly: the normal test run (CI);
  "nightly"         TEXELPAD_FUZZ_CASES (default NIGHTLY_CASES, 10,000) cases
                    per target, fresh random ones (never derandomized): the
                    nightly job, tools/fuzz.sh;
  "off"             the fuzz tests are skipped.
TEXELPAD_FUZZ_CASES overrides the count in either mode.

Known bugs: an outcome a target must not have, whose cause is known and
reported but lives in a layer the fuzz job does not fix (the link, the
device), is listed in KNOWN with a matcher. A target counts such a case
(STATS[...]["known"]) and goes on, so the smoke run stays green and the
nightly report says how often each one came up, with its first example;
TEXELPAD_FUZZ_STRICT=1 makes them failures again (to check a fix, or to let
hypothesis shrink one). An outcome that matches no entry fails the test.

STATS (target -> figures) is filled by the targets and printed / written by
tests/fuzz/conftest.py (TEXELPAD_FUZZ_REPORT=path.json).
"""
from __future__ import annotations

import collections
import contextlib
import os
import signal
import time
import traceback
from dataclasses import dataclass, field
from typing import Any, Callable

from hypothesis import settings

from support import hyp_profiles  # noqa: F401 (registers the profiles)

SMOKE_CASES = 50
NIGHTLY_CASES = 10_000
MODES = ("smoke", "nightly", "off")


def mode() -> str:
    m = (os.environ.get("TEXELPAD_FUZZ") or "smoke").strip().lower()
    if m in ("0", "no", "false"):
        m = "off"
    if m not in MODES:
        raise ValueError("TEXELPAD_FUZZ=%s: expected one of %s" % (m, ", ".join(MODES)))
    return m


def cases() -> int:
    env = os.environ.get("TEXELPAD_FUZZ_CASES")
    if env:
        return int(env)
    return NIGHTLY_CASES if mode() == "nightly" else SMOKE_CASES


def strict() -> bool:
    return os.environ.get("TEXELPAD_FUZZ_STRICT", "") not in ("", "0")


def randomized() -> bool:
    """Fresh random cases: always in the nightly mode; in the smoke mode only
    with TEXELPAD_HYPOTHESIS=nightly (else derandomized: CI is deterministic)."""
    return mode() == "nightly" or os.environ.get("TEXELPAD_HYPOTHESIS") == "nightly"


def fuzz_settings(**overrides: Any) -> settings:
    """The settings of every fuzz target: the project's hypothesis profiles
    (tests/conftest.py: no example database, no deadline, print_blob), the
    case count of the mode, derandomized only in a plain smoke run."""
    base = settings.get_profile("texelpad-nightly" if randomized() else "texelpad-default")
    return settings(base, max_examples=cases(), **overrides)


# --- figures -----------------------------------------------------------------------------

@dataclass
class Stats:
    cases: int = 0
    seconds: float = 0.0        # in the cases (the code under test and the checks)
    wall: float = 0.0           # the whole test, hypothesis' generation and shrinking included
    slowest: float = 0.0
    slowest_case: str = ""
    outcomes: collections.Counter = field(default_factory=collections.Counter)
    known: collections.Counter = field(default_factory=collections.Counter)
    known_first: dict = field(default_factory=dict)
    failures: list = field(default_factory=list)

    def as_dict(self) -> dict:
        return {"cases": self.cases, "seconds": round(self.seconds, 2),
                "wall_s": round(self.wall, 1),
                "slowest_case_s": round(self.slowest, 3), "slowest_case": self.slowest_case,
                "outcomes": dict(sorted(self.outcomes.items())),
                "known_bugs": {k: {"count": n, "first": self.known_first.get(k, "")}
                               for k, n in sorted(self.known.items())},
                "failures": self.failures}


STATS: dict[str, Stats] = collections.defaultdict(Stats)


def merge(figures: dict) -> None:
    """Add a worker's STATS (name -> Stats.as_dict(), as pytest-xdist hands
    them to the controller: tests/conftest.py) into this process's STATS."""
    for name, d in figures.items():
        s = STATS[name]
        s.cases += d["cases"]
        s.seconds += d["seconds"]
        s.wall += d["wall_s"]
        if d["slowest_case_s"] > s.slowest:
            s.slowest, s.slowest_case = d["slowest_case_s"], d["slowest_case"]
        s.outcomes.update(d["outcomes"])
        for k, v in d["known_bugs"].items():
            s.known[k] += v["count"]
            s.known_first.setdefault(k, v["first"])
        s.failures.extend(d["failures"])


@contextlib.contextmanager
def case(target: str, describe: Callable[[], str] = lambda: ""):
    """One case of `target`: counted and timed (real time) into STATS."""
    s = STATS[target]
    t0 = time.perf_counter()
    try:
        yield s
    finally:
        dt = time.perf_counter() - t0
        s.cases += 1
        s.seconds += dt
        if dt > s.slowest:
            s.slowest = dt
            try:
                s.slowest_case = describe()[:300]
            except Exception:                       # noqa: BLE001 - a description only
                s.slowest_case = "?"


def short(v: Any, n: int = 300) -> str:
    try:
        text = repr(v)
    except Exception:                               # noqa: BLE001
        text = "<%s>" % type(v).__name__
    return text if len(text) <= n else text[:n] + "... (%d characters)" % len(text)


# --- known bugs ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Known:
    id: str
    where: str          # the file to fix
    what: str           # one line
    match: Callable[[BaseException, list], bool]   # (exception, traceback frames) -> bool


def _frames(e: BaseException) -> list:
    return traceback.extract_tb(e.__traceback__)


def _raised_in(frames: list, path_part: str, func: str | None = None) -> bool:
    return any(path_part in f.filename and (func is None or f.name == func) for f in frames)


def known(e: BaseException) -> tuple[Known, str] | None:
    """The known bug e is, and its name in the report (the id, and for a
    matcher that returns text, that text: where it was raised)."""
    frames = _frames(e)
    for k in KNOWN:
        try:
            m = k.match(e, frames)
        except Exception:                           # noqa: BLE001 - a matcher's own bug
            continue
        if m:
            return k, (k.id if m is True else "%s %s" % (k.id, m))
    return None


def allow_known(target: str, e: BaseException, example: Callable[[], str]) -> None:
    """e is a forbidden outcome: count it if it is a known bug (and not
    strict), else raise it."""
    hit = known(e)
    if hit is None or strict():
        raise e
    name = hit[1]
    s = STATS[target]
    s.known[name] += 1
    s.outcomes["known bug"] += 1
    if name not in s.known_first:
        s.known_first[name] = "%s: %s | input: %s" % (type(e).__name__, short(str(e), 300),
                                                      example()[:800])


def _host_frame(frames: list):
    """The innermost frame in the host package (where a bug would be fixed)."""
    for f in reversed(frames):
        if "/host/texelpad/" in f.filename.replace("\\", "/"):
            return f
    return None


def _answer_shape(e: BaseException, frames: list):
    """An exception of the kind a malformed (well-framed) answer causes,
    raised by host code that took the answer's shape on trust: 'file func'."""
    import binascii
    if isinstance(e, (TypeError, KeyError, IndexError, AttributeError, binascii.Error)) or (
            type(e) is ValueError):
        f = _host_frame(frames)
        if f is not None and ("/texelpad/link/" in f.filename or "/texelpad/cli/" in f.filename):
            return "(%s %s)" % (f.filename.split("/host/texelpad/")[-1], f.name)
    return False


# Filled from what the nightly job found (docs/testing.md lists them with
# reproductions); each entry is a bug outside the layers the fuzz job fixes.
def _cause(e: BaseException) -> BaseException | None:
    return getattr(e, "cause", None)


KNOWN: list[Known] = [
    # empty: the eight bugs the first nightly runs found outside the fuzz job's
    # layers (docs/testing.md) are fixed, each kept fixed by the targets
    # themselves (a hit fails) and by tests/fuzz/test_found.py
]


# --- a watchdog: a case that hangs fails instead of stopping the job -----------------------

class Hang(BaseException):
    """Raised into a case that ran past its watchdog (real time). A
    BaseException, so no `except Exception` in the code under test eats it."""


@contextlib.contextmanager
def watchdog(seconds: float, what: str = "case"):
    if not hasattr(signal, "setitimer"):
        yield
        return

    def fire(signum, frame):
        raise Hang("%s still running after %g s (real time): a hang" % (what, seconds))
    old = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
