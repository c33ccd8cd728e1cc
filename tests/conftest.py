import importlib.util
import json
import os
import shutil
import signal
import sys
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# Ctrl-C as a user's terminal gives it. A shell without job control starts a background job
# (`bash .ci/run &`, nohup) with SIGINT ignored, and an ignored signal stays ignored across
# exec: the commands the tests start (`texelpad virtual`, the lab) then never saw the
# SIGINT a test sends to stop them, and tests/host/test_cli_board.py waited out its 20 s. A
# signal with a handler goes back to its default in a new program, so one here is enough.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
sys.path.insert(0, str(Path(__file__).resolve().parent))     # support (tests/support)
# the research benchmarks (bench/: not in the installed package; they run as
# `python -m bench.NAME` from the repository root) for the tests that import them
if str(ROOT) not in sys.path:
    sys.path.append(str(ROOT))


def shared_dir() -> Path:
    env = os.environ.get("TEXELPAD_SHARED")
    return Path(env) if env else ROOT.parent / "shared"


@pytest.fixture(scope="session")
def golden_dir() -> Path:
    d = shared_dir() / "golden"
    if not d.is_dir():
        pytest.fail(f"golden data not found at {d} (set TEXELPAD_SHARED)")
    return d


# --- hypothesis profiles ------------------------------------------------------------
# The build properties (tests/gen/test_build_property.py, tests/runtime/
# test_scene_property.py, test_scene.py's validate-then-build) take their settings
# from one of two profiles, chosen by TEXELPAD_HYPOTHESIS:
#   unset / "default"  derandomized (the same cases on every run), bounded: CI;
#   "nightly"          fresh random cases, NIGHTLY_SCALE times as many per property
#                      (thousands), still no example database and no deadline.
# e.g.  TEXELPAD_HYPOTHESIS=nightly pytest -s -m "not slow" tests/gen/test_build_property.py
# The profiles are registered by tests/support/hyp_profiles.py, which those modules
# import (their hyp_settings repeat NIGHTLY_SCALE); they are not loaded globally, so
# other hypothesis tests keep their own settings - and a test file without hypothesis
# does not import it (1.5 s of a one-file run where bytecode is not cached).
HYPOTHESIS_PROFILES = ("default", "nightly")


# --- hypothesis' constants: the same pool in every test process -------------------
# Hypothesis (6.131 on) mixes into its draws the literal constants of the project's
# modules loaded when a property runs (hypothesis.internal.constants_ast), so what a
# derandomized property draws depends on what its process imported before it. On
# pytest-xdist workers (tools/test.sh) that is whichever test files a worker happened
# to run first: a CircuitPython build property once drew a 10.5 km display that the
# one-process order never did. So every test process imports every module of the
# project first (about 2 s), and the default profile's cases are the same on every
# run again, however the files are spread.
NOT_IMPORTED = ("texel.main", "texelpad.firmware.frozen_main")   # board scripts: they start the display


def import_every_module() -> list[str]:
    """Import texel, texelpad, bench and tools/*.py (as the tests that use
    them do: tools/ on sys.path); return the modules that do not import on
    CPython (the viper and board-hardware modules)."""
    import importlib
    import pkgutil
    tools = ROOT / "tools"
    if str(tools) not in sys.path:
        sys.path.append(str(tools))
    names = ["texel", "texelpad", "bench"] + sorted(f.stem for f in tools.glob("*.py"))
    failed = []
    for name in names:
        try:
            m = importlib.import_module(name)
        except Exception:                               # noqa: BLE001 - listed, not raised
            failed.append(name)
            continue
        for info in pkgutil.walk_packages(getattr(m, "__path__", []), name + "."):
            if info.name in NOT_IMPORTED or info.name.endswith(".__main__"):
                continue
            try:
                importlib.import_module(info.name)
            except Exception:                           # noqa: BLE001
                failed.append(info.name)
    return failed


def pytest_configure(config):
    name = os.environ.get("TEXELPAD_HYPOTHESIS", "default") or "default"
    if name not in HYPOTHESIS_PROFILES:
        raise pytest.UsageError("TEXELPAD_HYPOTHESIS=%s: expected one of %s"
                                % (name, ", ".join(HYPOTHESIS_PROFILES)))
    if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
        return                  # the pytest-xdist controller: it runs no test
    # Each test process (the run, or each pytest-xdist worker: tools/test.sh runs
    # two) announces the virtual boards its tests start in a folder of its own
    # (host/texelpad/sim/virtual.py registry_dir): a board another worker's test
    # runs, or one the developer has running, is never found by auto-detection.
    # Tests that need their own registry still set TEXELPAD_RUNTIME_DIR.
    global _RUNTIME_DIR
    _RUNTIME_DIR = tempfile.mkdtemp(prefix="texelpad-tests-run-")
    os.environ["TEXELPAD_RUNTIME_DIR"] = _RUNTIME_DIR


HEAVY = Path(__file__).resolve().parent / "heavy.txt"    # tools/heavy_tests.py writes it


@pytest.hookimpl(tryfirst=True)         # before -m deselects: the mark must be there
def pytest_collection_modifyitems(session, config, items):
    # the tests of the everyday lane that take half a second or more here: marked
    # heavy, which tools/test.sh --unit leaves out (--fast and CI run them)
    heavy = {ln.strip() for ln in HEAVY.read_text().splitlines()
             if ln.strip() and not ln.startswith("#")}
    for item in items:
        if item.nodeid in heavy or item.nodeid.split("::")[0] in heavy:    # a test, or a file
            item.add_marker(pytest.mark.heavy)


def pytest_collection_finish(session):
    # every module imported once the tests are known (after -m and -k took their
    # share), before any runs - but only where a hypothesis property will run (the
    # pool above): a test file without one starts in a fraction of a second
    if any(getattr(getattr(item, "obj", None), "is_hypothesis_test", False)
           for item in session.items):
        import_every_module()


def pytest_unconfigure(config):
    if _RUNTIME_DIR:
        shutil.rmtree(_RUNTIME_DIR, ignore_errors=True)


_RUNTIME_DIR = ""


# --- pytest-xdist: the fuzz targets' table (tests/fuzz/conftest.py) ----------------
# The controller collects nothing, so tests/fuzz/conftest.py is not loaded there:
# each worker hands its figures over (workeroutput), and they are merged and
# printed here, as one process would have printed them.
_FUZZ_FROM_WORKERS: list[str] = []


@pytest.hookimpl(optionalhook=True)
def pytest_testnodedown(node, error):
    out = getattr(node, "workeroutput", {}).get("fuzz_stats")
    if out:
        _FUZZ_FROM_WORKERS.append(out)


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    if not _FUZZ_FROM_WORKERS:
        return
    spec = importlib.util.spec_from_file_location(
        "texelpad_fuzz_conftest", Path(__file__).resolve().parent / "fuzz" / "conftest.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    for out in _FUZZ_FROM_WORKERS:
        mod.fuzzlib.merge(json.loads(out))
    mod.report(terminalreporter, exitstatus, config)
