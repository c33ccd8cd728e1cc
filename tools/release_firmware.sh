#!/usr/bin/env bash
# Build the texelpad firmware for every board folder in boards/ and write the .uf2 files with
# their SHA-256 sums into OUT (default dist/firmware/): the release assets a maker downloads
# (docs/firmware.md). Needs Debian's gcc-arm-none-eabi libnewlib-arm-none-eabi cmake and a
# MicroPython v1.28.0 tree (the offline kit, or MICROPYTHON=DIR ULAB=DIR).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-dist/firmware}"
mkdir -p "$OUT"
extra=()
[ -n "${MICROPYTHON:-}" ] && extra+=(--micropython "$MICROPYTHON")
[ -n "${ULAB:-}" ] && extra+=(--ulab "$ULAB")
for d in boards/*/; do
    [ -f "$d/board.json" ] || continue
    name="$(basename "$d")"
    .venv/bin/texelpad firmware --board "$name" --out "build/firmware/$name" ${extra[@]+"${extra[@]}"}
    cp "build/firmware/$name/texelpad-$name.uf2" "$OUT/"
done
(cd "$OUT" && sha256sum texelpad-*.uf2 > SHA256SUMS && cat SHA256SUMS)
