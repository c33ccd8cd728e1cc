#!/usr/bin/env bash
# Set up (.venv with the package and its test tools) and run the test suite.
# This is the README's test command, and what .ci/run calls (everything): the
# lint (ruff) and the host's types (mypy), then the tests.
#
#   bash tools/test.sh            every test (CI)
#   bash tools/test.sh --fast     the development slice: -m "not slow" (about 6 minutes)
#   bash tools/test.sh --unit     the everyday lane: no virtual board, no instruments, no
#                                 emulated chip, no fuzz target, nothing slow, no test of half a
#                                 second or more (heavy: tests/heavy.txt, tools/heavy_tests.py);
#                                 pip only when pyproject.toml changed, the lint but not mypy
#   bash tools/test.sh ARGS...    any pytest arguments (a file, -k, -x ...)
#
# The tests run on two pytest-xdist workers, a test file to a worker (loadfile:
# a file's module fixtures - a lab process, a browser, a booted emulated Pico -
# are set up once). TEXELPAD_TEST_WORKERS=N sets how many; 0 runs them in this
# one process (then -s shows what tests print, e.g. the measured figures).
set -euo pipefail
cd "$(dirname "$0")/.."
args=()
unit=0
for a in "$@"; do
    case "$a" in
        --fast) args+=(-m "not slow") ;;
        --unit) unit=1; args+=(-m "not slow and not vboard and not instruments and not fuzz and not heavy") ;;
        *) args+=("$a") ;;
    esac
done
[ -x .venv/bin/python ] || python3 -m venv .venv
# pip again only when what it installs from changed (the stamp: pyproject.toml's hash)
stamp=.venv/.texelpad-installed
want=$(sha256sum pyproject.toml | cut -d' ' -f1)
if [ "$unit" = 0 ] || [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
    .venv/bin/python -m pip install -q --upgrade pip >/dev/null
    .venv/bin/python -m pip install -q -e '.[test]'
    echo "$want" > "$stamp"
fi
# the lint and the types first (pyproject.toml: [tool.ruff], [tool.mypy]); each takes
# seconds, and a red one stops here with what it found
.venv/bin/python -m ruff check --quiet host device tools tests bench
if [ "$unit" = 0 ]; then
    .venv/bin/python -m mypy --no-error-summary               # host/texelpad ([tool.mypy] files)
    .venv/bin/python -m mypy --no-error-summary bench         # the research benchmarks, on their own
fi
# the full run lists its slowest tests: where CI's minutes go (its aim: 25 on 2 cores)
if [ "$unit" = 0 ] && [ "$#" = 0 ]; then args+=(--durations=25); fi
workers="${TEXELPAD_TEST_WORKERS:-2}"
xdist=()
if [ "$workers" != 0 ]; then xdist=(-n "$workers" --dist loadfile); fi
exec .venv/bin/python -m pytest -q ${xdist[@]+"${xdist[@]}"} ${args[@]+"${args[@]}"}
