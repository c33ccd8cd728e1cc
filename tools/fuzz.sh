#!/usr/bin/env bash
# The nightly fuzz job (docs/testing.md): the fuzz targets of tests/fuzz -
# scenes, command-line flags, link framing, texelpad lab's HTTP API - with
# 10,000 fresh random cases each (never derandomized), outside CI's time
# budget. CI runs the same targets with 50 cases each (plain pytest:
# TEXELPAD_FUZZ unset = smoke). The lab target (a `texelpad lab` on the
# virtual board, 127.0.0.1 only) is also bounded in time: its cases after
# TEXELPAD_FUZZ_LAB_SECONDS (1,200 s nightly, 60 s in the smoke run) are
# counted "over time" and not run.
#
#   bash tools/fuzz.sh                        every target, 10,000 cases each
#   TEXELPAD_FUZZ_CASES=50000 bash tools/fuzz.sh
#   bash tools/fuzz.sh -k link                any pytest arguments (one target)
#   TEXELPAD_FUZZ_LAB_SECONDS=3600 bash tools/fuzz.sh -k lab    the lab API for an hour
#   TEXELPAD_FUZZ_SEED=1234 bash tools/fuzz.sh    the same cases again (same code)
#   TEXELPAD_FUZZ_STRICT=1 bash tools/fuzz.sh     known bugs fail too (to check a fix)
#
# Prints per target: cases run, seconds, failures, known bugs hit (and
# hypothesis' statistics); writes the same as JSON to $TEXELPAD_FUZZ_REPORT
# (default build/fuzz/report.json) and the whole output to build/fuzz/fuzz.log.
# One process; a 2-core machine shared with other work: nice bash tools/fuzz.sh
# TEXELPAD_SKIP_SETUP=1 uses .venv as it is (no pip run while other jobs use it).
set -euo pipefail
cd "$(dirname "$0")/.."
if [ "${TEXELPAD_SKIP_SETUP:-}" != 1 ]; then
    [ -x .venv/bin/python ] || python3 -m venv .venv
    .venv/bin/python -m pip install -q --upgrade pip >/dev/null
    .venv/bin/python -m pip install -q -e '.[test]'
fi
mkdir -p build/fuzz
seed="${TEXELPAD_FUZZ_SEED:-$(od -An -N4 -tu4 /dev/urandom | tr -d ' ')}"
export TEXELPAD_FUZZ=nightly TEXELPAD_HYPOTHESIS=nightly
export TEXELPAD_FUZZ_REPORT="${TEXELPAD_FUZZ_REPORT:-$PWD/build/fuzz/report.json}"
echo "fuzz: seed $seed (TEXELPAD_FUZZ_SEED=$seed replays it), ${TEXELPAD_FUZZ_CASES:-10000}" \
     "cases per target, report $TEXELPAD_FUZZ_REPORT"
.venv/bin/python -m pytest -q -p no:cacheprovider -m fuzz tests/fuzz \
    --hypothesis-seed="$seed" --hypothesis-show-statistics "$@" 2>&1 | tee build/fuzz/fuzz.log
