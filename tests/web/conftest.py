"""The web tests' lab: texelpad lab's app (starlette's TestClient) on a real
virtual board (the device image under the MicroPython unix port, on a pty),
one board per test module, a fresh data folder per test."""
from __future__ import annotations

import pytest
from starlette.testclient import TestClient

from texelpad.web.owner import BoardOwner
from texelpad.web.server import Lab, make_app

from support.vboard import virtual_board

BASE = "http://127.0.0.1"


@pytest.fixture(scope="module")
def port():
    with virtual_board() as p:
        yield p


@pytest.fixture
def lab(port, tmp_path):
    owner = BoardOwner(port, "virtual", realtime=True)
    lab = Lab(owner, tmp_path / "data")
    with TestClient(make_app(lab), base_url=BASE) as c:
        c.lab = lab
        yield c
    owner.close()
    lab.close()
