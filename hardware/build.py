"""Build texelpad's driver-board circuits (hardware/circuits/): for each circuit a
KiCad 6 netlist (.net), a BOM (.csv), the netlistsvg input (.json) and its schematic
drawing (.svg), after SKiDL's electrical rules check (strict: an unconnected pin or
two outputs on one net fail it).

    python hardware/build.py                 write hardware/design/
    python hardware/build.py --out DIR       write DIR instead
    python hardware/build.py --check         build into a scratch folder and list the
                                             committed files that differ (exit 1)
    python hardware/build.py --no-svg        skip the drawings (no node/npm)

The drawing needs node and the npm package netlistsvg; it is installed on first use
into ~/.cache/texelpad/netlistsvg (npm install --prefix), outside the checkout.
"""
from __future__ import annotations

import argparse
import filecmp
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

DESIGN = HERE / "design"
NETLISTSVG_VERSION = "1.0.2"
SUFFIXES = (".net", ".csv", ".json", ".svg")


def netlistsvg_dir() -> Path:
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache"))
    return cache / "texelpad" / "netlistsvg"


def netlistsvg(install: bool = True) -> Path | None:
    """The netlistsvg package folder (installing it if asked); None without node/npm."""
    pkg = netlistsvg_dir() / "node_modules" / "netlistsvg"
    if (pkg / "bin" / "netlistsvg.js").is_file():
        return pkg
    if not install or not shutil.which("node") or not shutil.which("npm"):
        return None
    print("build: installing netlistsvg %s into %s (npm, once)" % (NETLISTSVG_VERSION,
                                                                   netlistsvg_dir()))
    netlistsvg_dir().mkdir(parents=True, exist_ok=True)
    subprocess.run(["npm", "install", "--prefix", str(netlistsvg_dir()), "--no-audit",
                    "--no-fund", "--silent", "netlistsvg@" + NETLISTSVG_VERSION], check=True)
    return pkg if (pkg / "bin" / "netlistsvg.js").is_file() else None


def draw(json_path: Path, svg_path: Path, pkg: Path) -> None:
    subprocess.run(["node", str(pkg / "bin" / "netlistsvg.js"), str(json_path),
                    "--skin", str(pkg / "lib" / "analog.svg"), "-o", str(svg_path)],
                   check=True, capture_output=True)


def build_one(name: str, out: Path, pkg: Path | None):
    """Write name's files into out; return its ERC result."""
    from circuits import boards, erc, export
    built = boards.build(name)
    result = erc.check(built.circuit)
    if not result.ok:
        return result
    (out / (name + ".net")).write_text(export.netlist(built))
    (out / (name + ".csv")).write_text(export.bom_csv(built))
    (out / (name + ".json")).write_text(export.netlistsvg_json(built))
    if pkg is not None:
        draw(out / (name + ".json"), out / (name + ".svg"), pkg)
    return result


def build_all(out: Path, svg: bool = True) -> int:
    """Build every circuit into out; 0, or 1 after an ERC failure (listed)."""
    from circuits import boards, kicad
    why = kicad.why_missing()
    if why:
        print("build: error: " + why, file=sys.stderr)
        return 2
    pkg = netlistsvg() if svg else None
    if svg and pkg is None:
        print("build: error: no node/npm for netlistsvg (Debian: apt-get install nodejs npm)"
              " - or --no-svg", file=sys.stderr)
        return 2
    out.mkdir(parents=True, exist_ok=True)
    failed = 0
    for name in boards.CIRCUITS:
        res = build_one(name, out, pkg)
        print("build: %-13s ERC %s%s" % (name, res.summary(), "" if res.ok else ": FAILED"))
        for msg in res.messages:
            print("build:   " + msg)
        failed += not res.ok
    if failed:
        print("build: error: %d circuit(s) fail the electrical rules check; nothing written "
              "for them" % failed, file=sys.stderr)
        return 1
    return 0


def stale(fresh: Path, committed: Path, svg: bool = True) -> list[str]:
    """Committed files that differ from (or are missing against) a fresh build."""
    out = []
    for f in sorted(fresh.iterdir()):
        if f.suffix == ".svg" and not svg:
            continue
        mine = committed / f.name
        if not mine.is_file() or not filecmp.cmp(f, mine, shallow=False):
            out.append(str(mine))
    return out


def _shown(path: Path) -> str:
    """path relative to the working directory when it is under it."""
    try:
        return str(path.resolve().relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=DESIGN, help="output folder (hardware/design)")
    ap.add_argument("--check", action="store_true",
                    help="build into a scratch folder and fail on stale files in --out")
    ap.add_argument("--no-svg", action="store_true", help="skip the netlistsvg drawings")
    a = ap.parse_args(argv)
    if not a.check:
        rc = build_all(a.out, not a.no_svg)
        if rc == 0:
            print("build: wrote %s" % _shown(a.out))
        return rc
    with tempfile.TemporaryDirectory(prefix="texelpad-hw-") as tmp:
        rc = build_all(Path(tmp), not a.no_svg)
        if rc:
            return rc
        bad = stale(Path(tmp), a.out, not a.no_svg)
    for f in bad:
        print("build: stale: %s (run python hardware/build.py)" % f)
    print("build: %s" % ("%d stale file(s)" % len(bad) if bad else "design files up to date"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
