#!/usr/bin/env python3
"""Write tests/heavy.txt: the tests of the everyday lane (tools/test.sh --unit:
not slow, no virtual board, no instruments, no fuzz target) that take
HEAVY_S or more of setup + call + teardown on this machine, measured by
pytest --durations runs. tests/conftest.py marks them `heavy`, which --unit
leaves out (they still run in --fast and in CI). A module fixture's setup
moves to the next test when the first is left out, so it measures again
without the heavy ones found so far until no more turn up. Run it when --unit
has grown past a minute:

    .venv/bin/python tools/heavy_tests.py            # from scratch
    .venv/bin/python tools/heavy_tests.py --more     # keep the list, add to it
"""
import collections
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
HEAVY_S = 0.5
OUT = ROOT / "tests" / "heavy.txt"
UNIT = "not slow and not vboard and not instruments and not fuzz"
HEADER = ("# tests/heavy.txt: written by tools/heavy_tests.py (>= %.1f s each here; a file: its "
          "module fixture takes that); tools/test.sh --unit leaves them out\n" % HEAVY_S)


def measure() -> tuple[dict[str, float], set[str]]:
    """Seconds per test of the lane as it stands (heavy ones left out), and
    the files whose module fixtures take HEAVY_S or more to set up (every
    test of such a file shares them: the whole file is heavy)."""
    p = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "2", "--dist", "loadfile",
                        "-m", UNIT + " and not heavy", "-p", "no:cacheprovider",
                        "--durations=0", "--durations-min=0.005", "tests"],
                       cwd=ROOT, capture_output=True, text=True)
    took: dict[str, float] = collections.defaultdict(float)
    files: set[str] = set()
    for line in p.stdout.splitlines():
        m = re.match(r"([0-9.]+)s (setup|call|teardown)\s+(\S+)", line)
        if m:
            took[m.group(3)] += float(m.group(1))
            if m.group(2) == "setup" and float(m.group(1)) >= HEAVY_S:
                files.add(m.group(3).split("::")[0])
    if p.returncode != 0 or not took:
        sys.exit("the lane did not pass:\n" + p.stdout[-2000:] + p.stderr[-2000:])
    return took, files


def write(heavy: set[str]) -> None:
    OUT.write_text(HEADER + "".join(k + "\n" for k in sorted(heavy)))


def main() -> int:
    heavy: set[str] = set()
    if "--more" in sys.argv:
        heavy = {ln.strip() for ln in OUT.read_text().splitlines()
                 if ln.strip() and not ln.startswith("#")}
    write(heavy)
    for round_ in range(1, 6):
        took, files = measure()
        new = ({k for k, v in took.items() if v >= HEAVY_S and k.split("::")[0] not in files}
               | files) - heavy
        print("round %d: %d tests, %.0f s of test time, %d more heavy"
              % (round_, len(took), sum(took.values()), len(new)))
        if not new:
            break
        heavy |= new
        write(heavy)
    print("%d heavy tests: %s" % (len(heavy), OUT))
    return 0


if __name__ == "__main__":
    sys.exit(main())
