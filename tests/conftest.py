import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))


def shared_dir() -> Path:
    env = os.environ.get("TEXELPAD_SHARED")
    return Path(env) if env else ROOT.parent / "shared"


@pytest.fixture(scope="session")
def golden_dir() -> Path:
    d = shared_dir() / "golden"
    if not d.is_dir():
        pytest.fail(f"golden data not found at {d} (set TEXELPAD_SHARED)")
    return d
