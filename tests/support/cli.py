"""Run the texelpad command line in-process, as a test sees it."""
from __future__ import annotations

from texelpad.cli import main


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    """main(argv) -> (exit code, stdout, stderr); argparse's own exits too."""
    try:
        code = main(list(argv))
    except SystemExit as e:
        code = e.code
    out, err = capsys.readouterr()
    return code, out, err
