"""The electrical rules check: SKiDL's ERC, strict. SKiDL reports an unconnected
pin as a warning and two outputs on one net as an error; either fails here, so a
circuit passes only with 0 errors and 0 warnings (an intentionally unused pin is
marked NC in the circuit)."""
from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass, field

from . import kicad


@dataclass
class Result:
    errors: int = 0
    warnings: int = 0
    messages: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.errors == 0 and self.warnings == 0

    def summary(self) -> str:
        return "%d errors, %d warnings" % (self.errors, self.warnings)


class _Collect(logging.Handler):
    def __init__(self):
        super().__init__(logging.INFO)
        self.records: list = []

    def emit(self, record):
        if record.levelno >= logging.WARNING:
            self.records.append(record.getMessage())


@contextlib.contextmanager
def collecting(logger, quiet: bool = True):
    """Collect the warnings and errors logger reports inside the block (a list of
    messages); quiet: its own handlers (stderr, its log files) do not see them."""
    collect = _Collect()
    saved = list(logger.handlers)
    if quiet:
        for h in saved:
            logging.Logger.removeHandler(logger, h)     # keeps SKiDL's log-file bookkeeping
    logger.addHandler(collect)
    try:
        yield collect.records
    finally:
        logging.Logger.removeHandler(logger, collect)
        if quiet:
            for h in saved:
                logging.Logger.addHandler(logger, h)


def check(circuit, quiet: bool = True) -> Result:
    """Run SKiDL's ERC on circuit; its messages are collected (and not printed when
    quiet)."""
    kicad.skidl()
    from skidl.logger import erc_logger
    with collecting(erc_logger, quiet) as records:
        circuit.ERC()
        res = Result(erc_logger.error.count + erc_logger.bare_error.count,
                     erc_logger.warning.count + erc_logger.bare_warning.count)
    res.messages = sorted(records)
    return res
