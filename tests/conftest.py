import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
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
# The profiles are registered here and picked by those modules (their hyp_settings,
# which repeat NIGHTLY_SCALE); they are not loaded globally, so other hypothesis
# tests keep their own settings.
from hypothesis import HealthCheck, settings as _hyp_settings  # noqa: E402

HYPOTHESIS_PROFILES = ("default", "nightly")
NIGHTLY_SCALE = 25
_HYP_COMMON = dict(database=None, deadline=None, print_blob=True,
                   suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                          HealthCheck.filter_too_much,
                                          HealthCheck.large_base_example])
_hyp_settings.register_profile("texelpad-default", derandomize=True, **_HYP_COMMON)
_hyp_settings.register_profile("texelpad-nightly", derandomize=False, **_HYP_COMMON)


def pytest_configure(config):
    name = os.environ.get("TEXELPAD_HYPOTHESIS", "default") or "default"
    if name not in HYPOTHESIS_PROFILES:
        raise pytest.UsageError("TEXELPAD_HYPOTHESIS=%s: expected one of %s"
                                % (name, ", ".join(HYPOTHESIS_PROFILES)))
