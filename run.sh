#!/usr/bin/env bash
# ./run.sh [CASE.toml] [fdem run options]: install what is missing, build, run a case.
# With no case, runs the default wall case and prints its result against the experiment.
set -euo pipefail
cd "$(dirname "$0")"
source tools/setup.sh
case_file=${1:-cases/default.toml}
[ $# -gt 0 ] && shift
exec "$FDEM_BIN" run "$case_file" "$@"
