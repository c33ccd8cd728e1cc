"""The command line's parser and the argument types the commands share."""
from __future__ import annotations

import argparse
import math
import re
from typing import Any, NoReturn

from .errors import EXIT_USAGE, cut_repr

# What argparse takes for a negative number (a flag's value, not a flag): its
# own -5 and -.5, and also -1e5, -inf, -nan and quantities such as -1u (refused
# by their flag's type with one clear line), so `--pitch-db -inf` reaches the
# flag's check instead of "expected one argument". No texelpad flag looks like
# a negative number, so nothing is shadowed.
NEGATIVE_NUMBER = re.compile(r"^-(\d|\.\d|inf$|infinity$|nan$)", re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (plus a hint), exit 2, and
    negative numbers of every form are values (NEGATIVE_NUMBER)."""

    def __init__(self, *args: Any, **kwargs: Any):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER

    def error(self, message: str) -> NoReturn:
        # a value echoed by argparse is cut: `--seed 999...` of 5,000 digits
        # ("invalid int value: '999...'") stays one short line
        message = _LONG_QUOTED.sub(lambda m: cut_repr(m.group(1)), message)
        # an argument as typed may hold a line break: the error stays one line
        message = _CONTROL.sub(lambda m: repr(m.group())[1:-1], message)
        self.exit(EXIT_USAGE, "%s: error: %s (see: %s --help)\n" % (self.prog, message, self.prog))


_LONG_QUOTED = re.compile(r"'([^'\n]{41,})'")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def csv_list(text: str) -> list[str]:
    items = [s.strip() for s in text.split(",")]
    if not all(items):
        raise argparse.ArgumentTypeError("expected a comma-separated list, got %r" % text)
    return items


def positive_int(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("invalid int value: %r" % text) from None
    if v < 1:
        raise argparse.ArgumentTypeError("must be >= 1, got %d" % v)
    return v


def positive_float(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("invalid number: %r" % text) from None
    if not (v > 0 and math.isfinite(v)):
        raise argparse.ArgumentTypeError("must be a finite number > 0, got %s" % text)
    return v
