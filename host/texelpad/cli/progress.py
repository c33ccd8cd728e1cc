"""Upload progress on stderr (deploy, a large push)."""
from __future__ import annotations

import sys
from typing import Any


class ProgressBar:
    """Upload progress on stderr: a redrawn bar on a terminal, a line per
    file otherwise (logs, CI)."""

    def __init__(self, stream: Any = None, width: int = 30, label: str = "deploy"):
        self.stream = stream or sys.stderr
        self.label = label
        self.tty = self.stream.isatty()
        self.width = width
        self.last: str | None = None

    def __call__(self, done: int, total: int, name: str) -> None:
        frac = done / total if total else 1.0
        if self.tty:
            n = int(frac * self.width)
            self.stream.write("\r[%s%s] %3d%% %7s / %s bytes  %-32s" % (
                "#" * n, "." * (self.width - n), frac * 100, format(done, ","),
                format(total, ","), name[-32:]))
            self.stream.flush()
        elif name != self.last:
            self.stream.write("%s: %3d%% %s\n" % (self.label, frac * 100, name))
        self.last = name

    def end(self) -> None:
        if self.tty and self.last is not None:
            self.stream.write("\n")
