"""`texelpad encode`: a friction map -> the texel parameters that feel the same
(texelpad.analysis.encoder; docs/encoder.md)."""
from __future__ import annotations

import argparse
import json
import math
from typing import Any

from texel.gen.params import FORMAT_NEW

from .errors import EXIT_OK, CliError
from .files import check_output, write_output
from .parsing import positive_float, positive_int
from .scene_files import read_scene_file
from .texel_flags import FORMAT_HELP, PARAM_FLAGS

FIGURE_TYPES = (".png", ".pdf", ".svg")
# EncodeError messages start with what they are about; the flag it came from
_FLAG_OF = {"reference": "--reference", "length": "--length", "scene": "--scene",
            "region": "--region", "texel_samples": "--texel-samples", "quant_db": "--quant-db",
            "seed": "--seed", "v": "--format"}


def add_encode(p: argparse.ArgumentParser) -> None:
    p.description = (
        "Encode a friction map as Single-Pitch Texel parameters that feel the same: pitch and "
        "irregularity (and gain) chosen so that the texture's felt pitch and noisiness equal "
        "the map's (a model of what a sliding fingertip feels, calibrated on the trained "
        "rater's matches: docs/encoder.md). Prints the texture as JSON that pastes into a "
        "scene region, and the report: the felt points, both spectra on a log-frequency axis, "
        "the range of each parameter that feels the same, what quantization costs, the "
        "compression and the fraction of aliased texels. The map: "
        "a FILE (.csv: one number per line or a 'friction' column, as `texelpad render --out` "
        "writes it; .npy: float, or uint16 as a board stores it), a study reference "
        "(--reference) or a scene region (--scene, --region); one sample is 5.3 um.")
    p.add_argument("file", nargs="?", metavar="FILE", help="the map, .csv or .npy")
    src = p.add_argument_group("or the map from texelpad's own textures")
    src.add_argument("--reference", metavar="NAME",
                     help="a reference texture: 2sin 3sin 4sin white pink blue square "
                          "triangle sawtooth (seed 000's nine) or bp-<fc>-<zeta>")
    src.add_argument("--length", type=positive_int, metavar="N",
                     help="with --reference: samples (default 9600, the study's half screen)")
    src.add_argument("--scene", metavar="FILE",
                     help="a scene (JSON file, or a shipped scene: texelpad scenes): encode one "
                          "of its regions as the board plays it")
    src.add_argument("--region", type=positive_int, metavar="K",
                     help="with --scene: the K-th region by position (default 1)")
    tex = p.add_argument_group("the texture (fixed, not fitted)")
    tex.add_argument("--texel-samples", type=positive_int, default=50, metavar="N",
                     help="samples per texel (5.3 um each; default 50 = 0.265 mm, the lab's)")
    tex.add_argument("--quant-db", type=float, default=0.0, metavar="DB",
                     help="quantize the texture's log pitch to this grid, dB (default 0 = off)")
    tex.add_argument("--seed", type=int, default=0, metavar="N", help="the texture's seed")
    tex.add_argument("--format", dest="v", type=int, choices=(1, 2), default=FORMAT_NEW,
                     help=FORMAT_HELP)
    p.add_argument("--speed", type=positive_float, metavar="MM_S",
                   help="the finger's sliding speed in the perceptual model (default 86 mm/s)")
    p.add_argument("--method", choices=("felt", "w2"), default="felt",
                   help="felt (default): match the felt pitch and noisiness, as people "
                        "match; w2: match the whole felt spectrum (recovers a texel "
                        "rendering's own parameters, even above the skin's band)")
    p.add_argument("--no-ranges", action="store_true",
                   help="skip the scan for the range of each parameter that feels the same "
                        "(about half the time)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--figure", metavar="PATH",
                   help="write a figure (.png, .pdf, .svg): the map beside its decoding "
                        "(the texture rendered), the spectra, the felt distributions")
    p.set_defaults(func=cmd_encode)


def _error(e: ValueError, default_flag: str = "") -> CliError:
    """An encoder/validation error as one line naming its flag."""
    text = str(e)
    key, sep, rest = text.partition(": ")
    if sep and key in _FLAG_OF:
        return CliError(_FLAG_OF[key], rest)
    if sep and key in PARAM_FLAGS:
        return CliError(PARAM_FLAGS[key], rest)
    return CliError(default_flag, text)


def _load(args: argparse.Namespace) -> tuple[Any, str, list[str]]:
    """(map, its description, notes) from exactly one source."""
    from ..analysis import encoder as E
    given = [s for s, v in (("FILE", args.file), ("--reference", args.reference),
                            ("--scene", args.scene)) if v is not None]
    if len(given) != 1:
        raise CliError("", "give the map as one of FILE, --reference NAME or --scene FILE%s"
                       % (" (got %s)" % " and ".join(given) if given else ""))
    if args.length is not None and args.reference is None:
        raise CliError("--length", "goes with --reference (a file or scene has its own length)")
    if args.region is not None and args.scene is None:
        raise CliError("--region", "goes with --scene")
    try:
        if args.reference is not None:
            m = E.reference_map(args.reference, args.length)
            return m, "reference %s" % args.reference, []
        if args.scene is not None:
            scene = read_scene_file(args.scene)
            k = (args.region or 1) - 1
            m = E.scene_region_map(scene, k)
            return m, "scene %s region %d" % (args.scene, k + 1), []
        m, notes = E.read_map(args.file)
        return m, args.file, notes
    except E.EncodeError as e:
        raise _error(e, "FILE" if args.file is not None else "") from None


def cmd_encode(args: argparse.Namespace) -> int:
    from ..analysis import encoder as E
    from ..analysis import perception as P
    if not math.isfinite(args.quant_db):
        raise CliError("--quant-db", "must be a finite number, got %s" % args.quant_db)
    try:
        model = P.Model() if args.speed is None else P.Model(speed_mm_s=args.speed)
    except ValueError as e:
        raise CliError("--speed", str(e).partition(": ")[2]) from None
    fig = check_output("--figure", args.figure, FIGURE_TYPES) if args.figure else None
    fmap, source, notes = _load(args)
    try:
        res = E.encode(fmap, texel_samples=args.texel_samples, quant_db=args.quant_db,
                       seed=args.seed, v=args.v, model=model, intervals=not args.no_ranges,
                       source=source, method=args.method)
    except ValueError as e:                 # EncodeError, and validate's own
        raise _error(e) from None
    res["notes"] = notes + res["notes"]
    if fig is not None:
        from ..analysis.figures import encode_figure
        write_output("--figure", str(fig), lambda: encode_figure(fig, fmap, res))
        res["figure"] = str(fig)
    print(json.dumps(res, indent=1) if args.json else summary(res))
    return EXIT_OK


def summary(res: dict) -> str:
    """The report in words and one table (the spectra every 0.25 decade)."""
    tex = res["texture"]
    m = res["map"]
    lines = ["%s: %s samples (%.4g mm), mean %.3g, rms %.3g"
             % (res.get("source", "map"), format(m["samples"], ","), m["length_mm"], m["mean"],
                m["rms"]),
             "texture    %s" % scene_texture_json(tex),
             "           pitch %.2f dB (%.4g c/mm), irregularity %.2f dB (%.3g decade), gain %.4g"
             % (tex["pitch_db"], 10 ** (tex["pitch_db"] / 10), tex["irregularity_db"],
                10 ** (tex["irregularity_db"] / 10), tex["gain"])]
    fm, fr = res["felt"]["map"], res["felt"]["rendering"]
    lines.append("felt       pitch %.2f dB, noisiness %.2f dB (map); %.2f dB, %.2f dB (texture); "
                 "level %s dB re full scale"
                 % (fm["pitch_db"], fm["noisiness_db"], fr["pitch_db"], fr["noisiness_db"],
                    "%.1f" % fm["level_db"] if fm["level_db"] is not None else "-inf"))
    lines.append("distance   %.3f dB on the felt plane (pitch, noisiness; under %.2g dB feels the "
                 "same), %.3f dB between the felt spectra (2-Wasserstein)%s"
                 % (res["felt_distance_db"], res["model"]["jnd_db"], res["w2_distance_db"],
                    "" if res["method"] == "felt" else "; minimised: the second"))
    rg = res.get("ranges")
    if rg:
        lines.append("same feel  pitch %.2f .. %.2f dB, irregularity %.2f .. %.2f dB (within "
                     "%.3g dB, the other held)%s"
                     % (rg["pitch_db"][0], rg["pitch_db"][1], rg["irregularity_db"][0],
                        rg["irregularity_db"][1], rg["limit_db"], _unidentified(rg)))
    sb = res["skin_band"]
    lines.append("skin band  up to %.0f Hz at %g mm/s: %.3g c/mm (%.2f dB); a full-scale "
                 "modulation above it is not felt" % (sb["hz"][1], sb["speed_mm_s"],
                                                      sb["cpmm"][1], sb["pitch_db_max"]))
    qz = res.get("quantization")
    if qz:
        lines.append("quantized  distance with the pitch quantized to " + ", ".join(
            "%s dB: %.3f" % (k, v) for k, v in qz["cost_db"].items()))
    c = res["compression"]
    lines.append("compressed %s bytes (the map as uint16) -> %d bytes (the texture literal): "
                 "%gx" % (format(c["map_bytes"], ","), c["texture_bytes"], c["ratio"]))
    a = res["aliasing"]
    lines.append("aliasing   %.2f %% of texels expected above Nyquist (%.2f c/mm); %d of %d "
                 "drawn with seed %d; the map has %.2f %% of its power in the top 0.1 decade"
                 % (100 * a["expected_fraction"], a["nyquist_cpmm"], a["drawn_texels"],
                    a["texels"], tex["seed"], 100 * a["map_top_band_fraction"]))
    sp = res["spectrum"]
    lines.append("spectrum   band power (dB re full-scale sine) and share of the felt power (%)")
    lines.append("             c/mm     map  texture   felt map  felt texture")
    step = 5                    # every 5th reported point: 0.25 decade
    for k in range(0, len(sp["f_cpmm"]), step):
        fm_ = sum(sp["map_felt"][k:k + step])
        fr_ = sum(sp["rendering_felt"][k:k + step])
        lines.append("         %8.4g  %6.1f  %7.1f   %8.1f  %12.1f"
                     % (sp["f_cpmm"][k], sp["map_db"][k], sp["rendering_db"][k], 100 * fm_,
                        100 * fr_))
    for note in res["notes"]:
        lines.append("note       %s" % note)
    if res.get("figure"):
        lines.append("wrote      %s" % res["figure"])
    lines.append("encoded in %.3f s (%d candidate textures)" % (res["seconds"],
                                                              res["evaluations"]))
    return "\n".join(lines)


def scene_texture_json(tex: dict) -> str:
    """The texture as the JSON a scene region's "texture" takes (kind texel
    first), one line: it pastes into a scene file as it stands."""
    return json.dumps(dict({"kind": "texel"}, **tex))


def _unidentified(rg: dict) -> str:
    from ..analysis.encoder import BOUNDS
    words = []
    lo, hi = rg["irregularity_db"]
    if lo <= BOUNDS[1][0] + 0.01:
        words.append("any irregularity below %.1f dB feels the same" % hi)
    if hi - lo > 10 and lo > BOUNDS[1][0] + 0.01:
        words.append("the irregularity is loosely determined")
    if rg["pitch_db"][1] - rg["pitch_db"][0] > 6:
        words.append("the pitch is loosely determined")
    return (": " + "; ".join(words)) if words else ""
