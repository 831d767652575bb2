#!/usr/bin/env bash
# ./run.sh [CASE.toml] [fdem run options]: install what is missing, build, run a case.
# With no case, runs the default wall case (the 100 kN dry-stone wall of Lourenco et al. 2005, [K25] style, 25 mm, at
# the QUICK setting: the family's settings with mass scaling 100, about 2 minutes on 2 threads, see its header) and prints
# its peak load against the experiment.
set -euo pipefail
cd "$(dirname "$0")"
FDEM_BUILD_TARGET=${FDEM_BUILD_TARGET:-fdem}  # the executable only; ./test.sh builds the tests
source tools/setup.sh
case_file=${1:-cases/lourenco2005/k25_N100_quick.toml}
[ $# -gt 0 ] && shift
exec "$FDEM_BIN" run "$case_file" "$@"
