"""The texel parameter flags, derived from the device's own parameter spec
(texel.gen.params.SPEC): one flag per key (--pitch-db for pitch_db), typed
and ranged by the spec; the meaning of each key is the only thing written
here. Errors of the device's validation name the flag, not the key."""
from __future__ import annotations

import argparse
from typing import Any

from texel.gen.params import FORMAT_NEW, KEYS as TEXEL_SPEC_KEYS, QUANT_DB_MIN, SPEC as TEXEL_SPEC
from texel.gen.params import OPTION_KEYS, OPTION_SPEC, PHASES

from .errors import CliError

# One flag per key of texel.gen.params.SPEC (the format version "v" is
# --format).
TEXEL_MEANING = {
    "pitch_db": ("DB", "central pitch, 10*log10(P / 1 cycle/mm)"),
    "irregularity_db": ("DB", "irregularity, 10*log10(sigma / 1 decade)"),
    "texel_samples": ("N", "samples per texel (5.3 um each)"),
    "length_samples": ("N", "map length in samples of 5.3 um"),
    "quant_db": ("DB", "quantize log pitch to this grid, dB (0 = off)"),
    "seed": ("N", "random seed"),
    "gain": ("G", "map scale"),
    "band_limit_cpmm": ("F", "clamp drawn pitches to at most F cycles/mm (default: faithful, "
                             "pitches above Nyquist alias as in the original)"),
}
# in the spec's own order (texel.gen.params.KEYS); a new spec key needs a meaning here
TEXEL_KEYS = tuple(k for k in TEXEL_SPEC_KEYS if k != "v")
# The texture options (texel.gen.params.OPTION_SPEC: in a texture only when
# set; seed 001's stimulus, docs/generator.md), one flag each.
OPTION_MEANING = {
    "min_cpmm": ("F", "lower pitch bound, cycles/mm: a texel drawn below it is redrawn from a "
                      "second stream (seed 001's 1 c/mm; %g .. %g, below --band-limit-cpmm; "
                      "default: none)" % OPTION_SPEC["min_cpmm"][2:]),
    "phase": (None, "phase at texel borders: continuous (default, the original) or reset "
                    "(every texel starts at the first texel's phase, as in seed 001)"),
}
# texel parameter key -> its flag (error messages name the flag, not the key)
PARAM_FLAGS = {k: "--" + k.replace("_", "-") for k in TEXEL_KEYS + OPTION_KEYS}
PARAM_FLAGS["engine"] = "--engine"
PARAM_FLAGS["v"] = "--format"
FORMAT_HELP = ("texture format: 2 = the integer plan (default), the same texture bit for bit "
               "on every board and ~25x faster to start on an RP2040 (pitch, irregularity and "
               "quantization on a 0.001 dB grid); 1 = the lab's float plan, its exact "
               "generator (a texture saved without a format is format 1); docs/generator.md")


def _range_text(key: str) -> str:
    """"-20 .. 19.747", "0 or 0.001 .. 20, default 0": the spec's range."""
    kind, default, lo, hi = TEXEL_SPEC[key]

    def num(v: float) -> str:
        return format(v, ",") if kind == "i" else "%g" % v
    low = "0 or %s" % num(QUANT_DB_MIN) if key == "quant_db" else num(lo)
    text = "%s .. %s" % (low, num(hi))
    return text if default is None else text + ", default %s" % num(default)


def add_texel_flags(group: Any, keys: tuple[str, ...] = TEXEL_KEYS,
                    required: tuple[str, ...] = ()) -> None:
    """Add --<key> flags for these texel keys to a parser or argument group."""
    for key in keys:
        kind, _, _, _ = TEXEL_SPEC[key]
        metavar, meaning = TEXEL_MEANING[key]
        group.add_argument(PARAM_FLAGS[key], dest=key, type=int if kind == "i" else float,
                           metavar=metavar, required=key in required,
                           help="%s; %s" % (meaning, _range_text(key)))
    group.add_argument("--format", dest="v", type=int, choices=(1, 2), help=FORMAT_HELP)
    group.add_argument(PARAM_FLAGS["min_cpmm"], dest="min_cpmm", type=float,
                       metavar=OPTION_MEANING["min_cpmm"][0], help=OPTION_MEANING["min_cpmm"][1])
    group.add_argument(PARAM_FLAGS["phase"], dest="phase", choices=PHASES,
                       help=OPTION_MEANING["phase"][1])


def render_params(args: argparse.Namespace) -> dict[str, Any]:
    """The texel parameter dict from the flags that were given."""
    params: dict[str, Any] = {}
    for key in TEXEL_KEYS + ("v",) + OPTION_KEYS:
        v = getattr(args, key, None)
        if v is not None:
            params[key] = v
    if params and "v" not in params:
        params["v"] = FORMAT_NEW        # a new texture: format 2 unless --format says
    return params


def device_error(e: ValueError) -> CliError:
    """A device ValueError ("pitch_db: nan is not finite ...") as a CliError
    naming the flag instead of the parameter key."""
    text = str(e)
    key, sep, rest = text.partition(": ")
    if sep and key in PARAM_FLAGS:
        return CliError(PARAM_FLAGS[key], rest)
    missing = "missing required key '"
    if text.startswith(missing):
        key, _, more = text[len(missing):].partition("'")
        if key in PARAM_FLAGS:
            return CliError(PARAM_FLAGS[key], "required%s" % more)
    return CliError("", text)
