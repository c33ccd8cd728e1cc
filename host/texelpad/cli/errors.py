"""Exit codes and the one-line error of every texelpad command.

Errors in what the user typed print one line naming the flag and exit 2 (no
traceback); failures of the world (a file that cannot be written, no board,
a lost link) exit 1. main() prints a CliError as
"texelpad COMMAND: error: FLAG: MESSAGE" and exits with its code.
"""
from __future__ import annotations

import sys

EXIT_OK = 0
EXIT_FAIL = 1
EXIT_USAGE = 2


class CliError(Exception):
    """A bad command-line value: printed as one line, exit 2."""

    def __init__(self, flag: str, message: str, code: int = EXIT_USAGE):
        super().__init__("%s: %s" % (flag, message) if flag else message)
        self.code = code


def cut_repr(text: str, n: int = 40) -> str:
    """repr(text), cut to n characters: error lines stay one short line."""
    return repr(text) if len(text) <= n else repr(text[:n]) + "... (%s characters)" % format(
        len(text), ",")


def to_stderr(msg: str) -> None:
    """One line on stderr, flushed: progress, warnings, the error line."""
    print(msg, file=sys.stderr, flush=True)
