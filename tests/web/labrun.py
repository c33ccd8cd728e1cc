"""`texelpad lab` as a process with everything a robustness test needs: its
own TMPDIR (so a virtual board's flash folder left behind is seen), its
stderr kept in a file, any arguments, a stop by a chosen signal; and raw HTTP
over a socket, for clients no library would be: a body that trickles or
stalls, a Content-Length of 300 MB. 127.0.0.1 only."""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path
from typing import Any


class LabRun:
    def __init__(self, data: Path, *args: str, tmp: Path | None = None) -> None:
        self.data = Path(data)
        self.tmp = Path(tmp) if tmp else self.data.parent / ("%s-tmp" % self.data.name)
        self.tmp.mkdir(parents=True, exist_ok=True)
        self.args = list(args)
        self.p: subprocess.Popen | None = None
        self.url = ""
        self.err_path = self.tmp.parent / ("%s-stderr-%d.txt" % (self.data.name, time.time_ns()))

    def start(self, wait: bool = True, timeout: float = 60.0) -> "LabRun":
        env = dict(os.environ, TMPDIR=str(self.tmp))
        self._err = open(self.err_path, "w")
        self.p = subprocess.Popen([sys.executable, "-m", "texelpad", "lab", "--data",
                                   str(self.data)] + self.args, stdout=subprocess.PIPE,
                                  stderr=self._err, text=True, env=env)
        self.url = self.p.stdout.readline().strip()
        if wait:
            assert self.url.startswith("http://127.0.0.1:"), (self.url, self.stderr())
            deadline = time.monotonic() + timeout
            while True:
                try:
                    self.get("api/status", timeout=5)
                    break
                except OSError:
                    if time.monotonic() > deadline or self.p.poll() is not None:
                        raise
                    time.sleep(0.2)
        return self

    @property
    def port(self) -> int:
        return int(self.url.rsplit(":", 1)[1].strip("/"))

    def stderr(self) -> str:
        try:
            return self.err_path.read_text()
        except OSError:
            return ""

    def stop(self, sig: int = signal.SIGTERM, timeout: float = 30.0) -> int:
        """Send sig and wait for the end (SIGKILL after timeout: then raise)."""
        if self.p is None:
            return 0
        if self.p.poll() is None:
            self.p.send_signal(sig)
        try:
            rc = self.p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait()
            raise AssertionError("texelpad lab did not stop within %g s of signal %d"
                                 % (timeout, sig)) from None
        finally:
            self._err.close()
        return rc

    def flash_left(self) -> list[str]:
        return sorted(p.name for p in self.tmp.glob("texelpad-flash-*"))

    def __enter__(self) -> "LabRun":
        return self.start()

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    # --- HTTP -----------------------------------------------------------------------
    def get(self, path: str, timeout: float = 30) -> Any:
        with urllib.request.urlopen(self.url + path, timeout=timeout) as r:
            return json.loads(r.read())

    def post(self, path: str, body: Any, timeout: float = 30) -> tuple[int, Any]:
        req = urllib.request.Request(self.url + path, data=json.dumps(body).encode(),
                                     headers={"content-type": "application/json"},
                                     method="POST")
        try:
            with urllib.request.urlopen(req, timeout=timeout) as r:
                return r.status, json.loads(r.read())
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read() or b"{}")


def raw_head(port: int, method: str, path: str, length: int | None,
             ctype: str = "application/json", timeout: float = 30,
             extra: str = "") -> socket.socket:
    """A socket that has sent a request's headers (Content-Length: length,
    none when None; extra: more header lines, each ending in CRLF) and no
    body yet."""
    s = socket.create_connection(("127.0.0.1", port), timeout=timeout)
    head = "%s %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\nContent-Type: %s\r\n%s" % (
        method, path, port, ctype, extra)
    if length is not None:
        head += "Content-Length: %d\r\n" % length
    s.sendall((head + "\r\n").encode())
    return s


def read_response(s: socket.socket) -> tuple[int, dict]:
    """(status, JSON body) of the response on s (read until it is whole)."""
    buf = b""
    while b"\r\n\r\n" not in buf:
        chunk = s.recv(65536)
        if not chunk:
            break
        buf += chunk
    head, _, rest = buf.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    hdrs = {k.strip().lower(): v.strip() for k, _, v in (x.partition(":") for x in lines[1:])}
    n = int(hdrs.get("content-length", "0"))
    while len(rest) < n:
        chunk = s.recv(65536)
        if not chunk:
            break
        rest += chunk
    try:
        return status, json.loads(rest[:n] or b"{}")
    except ValueError:
        return status, {"raw": rest[:200].decode("latin-1")}


def rss_kb(pid: int) -> int:
    for line in Path("/proc/%d/status" % pid).read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return -1
