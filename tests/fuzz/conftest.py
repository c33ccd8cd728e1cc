"""The fuzz targets (tests/fuzz/test_*.py, each marked `fuzz`): sized by
TEXELPAD_FUZZ (fuzzlib: "smoke" by default - 50 cases each, a few seconds,
part of the normal run; "nightly" - 10,000 fresh random cases each, run by
tools/fuzz.sh; "off" - skipped), and reported: a table of cases, seconds,
known bugs hit and failures per target at the end of the run, and the same
as JSON at TEXELPAD_FUZZ_REPORT when that is set.

Why a size switch and not a deselecting marker: the targets are the same
code at both sizes, and CI runs them small (plain `pytest -q`, which
tools/test.sh is). A second `-m` would override tools/test.sh --fast's
`-m "not slow"`, and addopts cannot deselect what CI must still run. The
`fuzz` marker selects them (`pytest -m fuzz`) or leaves them out
(`-m "not fuzz"`).
"""
from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

import fuzzlib  # noqa: E402

HERE = Path(__file__).resolve().parent
_T0 = time.time()


def pytest_collection_modifyitems(config, items):
    if fuzzlib.mode() != "off":
        return
    for item in items:
        if _target(item) is not None:
            item.add_marker(pytest.mark.skip(reason="TEXELPAD_FUZZ=off"))


def _target(item) -> str | None:
    """The target a test feeds: its module's FUZZ_TARGET."""
    return getattr(getattr(item, "module", None), "FUZZ_TARGET", None)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    target = _target(item)
    if target is None or rep.when != "call":
        return
    fuzzlib.STATS[target].wall += rep.duration
    if not rep.failed or call.excinfo is None:
        return
    e = call.excinfo.value
    errors = list(e.exceptions) if isinstance(e, BaseExceptionGroup) else [e]  # noqa: F821 (3.11)
    for x in errors:
        fuzzlib.STATS[target].failures.append(
            {"type": type(x).__name__, "message": fuzzlib.short(str(x), 600)})


def pytest_sessionfinish(session, exitstatus):
    """A pytest-xdist worker hands its figures to the controller, which does
    not load this file (it collects nothing): tests/conftest.py merges them
    and prints the table with report() below."""
    out = getattr(session.config, "workeroutput", None)
    if out is not None and fuzzlib.STATS:
        out["fuzz_stats"] = json.dumps({n: s.as_dict() for n, s in fuzzlib.STATS.items()},
                                       default=str)


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    report(terminalreporter, exitstatus, config)


def report(terminalreporter, exitstatus, config):
    if not fuzzlib.STATS:
        return
    tr = terminalreporter
    tr.section("fuzz targets (TEXELPAD_FUZZ=%s, %s)" % (
        fuzzlib.mode(), "random" if fuzzlib.randomized() else "derandomized"))
    tr.write_line("%-8s %8s %8s %9s %8s  %s" % ("target", "cases", "wall s", "in cases",
                                                 "failures", "known bugs hit"))
    for name, s in sorted(fuzzlib.STATS.items()):
        tr.write_line("%-8s %8d %8.1f %9.1f %8d  %s" % (
            name, s.cases, s.wall, s.seconds, len(s.failures),
            ", ".join("%s x%d" % kv for kv in sorted(s.known.items())) or "-"))
    for name, s in sorted(fuzzlib.STATS.items()):
        for f in s.failures:
            tr.write_line("%s: FAILURE %s: %s" % (name, f["type"], f["message"][:300]))
        for k, first in sorted(s.known_first.items()):
            tr.write_line("%s: known %s, first: %s" % (name, k, first[:300]))
    path = os.environ.get("TEXELPAD_FUZZ_REPORT")
    if path:
        report = {"mode": fuzzlib.mode(), "randomized": fuzzlib.randomized(),
                  "cases_per_target": fuzzlib.cases(), "strict": fuzzlib.strict(),
                  "seed": config.getoption("hypothesis_seed", None),
                  "started": time.strftime("%Y-%m-%dT%H:%M:%S", time.localtime(_T0)),
                  "wall_s": round(time.time() - _T0, 1), "exitstatus": int(exitstatus),
                  "known_bugs": {k.id: {"where": k.where, "what": k.what} for k in fuzzlib.KNOWN},
                  "targets": {n: s.as_dict() for n, s in sorted(fuzzlib.STATS.items())}}
        Path(path).write_text(json.dumps(report, indent=1, default=str) + "\n", encoding="utf-8")
        tr.write_line("fuzz report: %s" % path)
