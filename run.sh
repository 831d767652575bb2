#!/usr/bin/env bash
# ./run.sh [CASE.toml] [fdem run options]: install what is missing, build, run a case.
# With no case, runs the default wall case (the 100 kN dry-stone wall of Lourenco et al. 2005, [K25] style, 25 mm, at
# the QUICK setting: the family's settings with per-node mass scaling 15, under a minute on 2 threads, see its header) and prints
# its peak load against the experiment.
set -euo pipefail
cd "$(dirname "$0")"
FDEM_BUILD_TARGET=${FDEM_BUILD_TARGET:-fdem}  # the executable only; ./test.sh builds the tests
source tools/setup.sh
# The first argument is the case unless it is an option (`./run.sh --threads 2` runs the default case).
case_file=cases/lourenco2005/k25_N100_quick.toml
if [ $# -gt 0 ] && [ "${1#-}" = "$1" ]; then case_file=$1; shift; fi
exec "$FDEM_BIN" run "$case_file" "$@"
