"""`texelpad lab` as a process for the web tests: started on the virtual
board with a data folder, its URL read from the first line, stopped with
SIGTERM (as Ctrl-C would) on the way out."""
from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
import urllib.request
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator


@contextmanager
def lab_process(data: Path, timeout: float = 30.0) -> Iterator[tuple[str, dict]]:
    """(URL, the board status the server answered first)."""
    p = subprocess.Popen([sys.executable, "-m", "texelpad", "lab", "--data", str(data)],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = p.stdout.readline().strip()
        assert url.startswith("http://127.0.0.1:") and url.endswith("/"), url
        deadline = time.monotonic() + timeout
        while True:
            try:
                with urllib.request.urlopen(url + "api/status", timeout=5) as r:
                    st = json.loads(r.read())
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.2)
        yield url, st
    finally:
        p.send_signal(signal.SIGTERM)
        try:
            p.wait(timeout=30)
        except subprocess.TimeoutExpired:
            p.kill()
            raise
