"""SKiDL set up for KiCad 6 with the Debian KiCad 6 libraries, in code.

The symbol and footprint folders are fixed here (Debian's kicad-symbols and
kicad-footprints 6.0), so nobody has to export KICAD6_SYMBOL_DIR or keep an
fp-lib-table in ~/.config/kicad. SKiDL reads its configuration (.skidlcfg) from
the working directory at import time, and opens log files there: the import
runs in a scratch folder holding a .skidlcfg with these paths, and the log
files are closed and removed before it leaves, so nothing lands in the checkout
and SKiDL prints none of its missing-library warnings.
"""
from __future__ import annotations

import json
import logging
import os
import tempfile
from pathlib import Path

SYMBOL_DIR = Path("/usr/share/kicad/symbols")
FOOTPRINT_DIR = Path("/usr/share/kicad/footprints")
# every backend SKiDL 3.0 knows: a tool missing from .skidlcfg gets the
# defaults again, and with them the environment-variable warnings
TOOLS = ("kicad5", "kicad6", "kicad7", "kicad8", "kicad9", "kicad10", "skidl", "spice")

_skidl = None


def why_missing() -> str | None:
    """Why the circuits cannot be built here (None: they can)."""
    import importlib.util
    # found, not imported: importing skidl here would do it in the working directory
    if importlib.util.find_spec("skidl") is None:
        return "skidl is not installed (pip install 'skidl==3.0.0')"
    if not (SYMBOL_DIR / "Device.kicad_sym").is_file():
        return "KiCad 6 symbols missing at %s (Debian: apt-get install kicad-symbols)" % SYMBOL_DIR
    if not (FOOTPRINT_DIR / "Resistor_SMD.pretty").is_dir():
        return ("KiCad 6 footprints missing at %s (Debian: apt-get install kicad-footprints)"
                % FOOTPRINT_DIR)
    return None


def fp_lib_table(folder: Path) -> Path:
    """Write a KiCad fp-lib-table naming every footprint library of FOOTPRINT_DIR."""
    rows = ['  (lib (name "%s")(type "KiCad")(uri "%s")(options "")(descr ""))'
            % (p.stem, p) for p in sorted(FOOTPRINT_DIR.glob("*.pretty"))]
    path = folder / "fp-lib-table"
    path.write_text("(fp_lib_table\n%s\n)\n" % "\n".join(rows))
    return path


def skidl():
    """The skidl module, imported once, configured for KiCad 6 and these libraries."""
    global _skidl
    if _skidl is not None:
        return _skidl
    cache = Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "texelpad" / "kicad6"
    cache.mkdir(parents=True, exist_ok=True)
    fp_lib_table(cache)
    cfg = {"tool": "kicad6",
           "lib_search_paths": {t: [str(SYMBOL_DIR)] for t in TOOLS},
           "footprint_search_paths": {t: [str(cache)] for t in TOOLS}}
    here = os.getcwd()
    logger_class = logging.getLoggerClass()     # SKiDL's import replaces it process-wide
    with tempfile.TemporaryDirectory(prefix="texelpad-skidl-") as scratch:
        (Path(scratch) / ".skidlcfg").write_text(json.dumps(cfg))
        os.chdir(scratch)
        try:
            import skidl as sk
            from skidl.logger import stop_log_file_output
            stop_log_file_output()          # closes and deletes <script>.log / .erc
        finally:
            os.chdir(here)
            logging.setLoggerClass(logger_class)
    sk.set_default_tool(sk.KICAD6)
    sk.lib_search_paths[sk.KICAD6] = [str(SYMBOL_DIR)]
    sk.empty_footprint_handler = _no_empty_footprint
    _skidl = sk
    return sk


def _no_empty_footprint(part) -> None:
    raise ValueError("%s (%s) has no footprint: every part needs one" % (part.ref, part.name))
