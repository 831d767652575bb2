#!/usr/bin/env bash
# ./test.sh [ctest options]: install what is missing, build, run every test (C++ and Python).
# The long validation runs carry the ctest label "validation" and are excluded here;
# run them with:  ./test.sh -L validation
set -euo pipefail
cd "$(dirname "$0")"
source tools/setup.sh
jobs=$(nproc 2>/dev/null || echo 2)
if [ $# -eq 0 ]; then
  set -- -LE validation
fi
cd "$FDEM_BUILD"
exec ctest --output-on-failure --parallel "$jobs" "$@"
