#!/bin/sh
# cmake --install into a fresh prefix, as a cluster user without root does (--prefix ~/.local), then the installed
# fdem, fdem_bench and fdem-tools start from that prefix alone (fdem-tools finds its Python package and the fdem
# next to it). Usage: check_install.sh BUILD_DIR PREFIX
set -eu
build=$1
prefix=$2
rm -rf "$prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
"$prefix/bin/fdem" --version
[ -x "$prefix/bin/fdem_bench" ]
"$prefix/bin/fdem-tools" --help | grep -q "usage: fdem-tools"
# fdem-tools is not the repository's copy: run it from a folder without the repository on its path.
cd /
env -u FDEM_BIN "$prefix/bin/fdem-tools" --help >/dev/null
# The installed tools use the installed fdem: the launcher sets FDEM_BIN and runs $FDEM_PYTHON when given.
printf '#!/bin/sh\necho "FDEM_BIN=$FDEM_BIN"\n' >"$prefix/show_env"
chmod +x "$prefix/show_env"
got=$(env -u FDEM_BIN FDEM_PYTHON="$prefix/show_env" "$prefix/bin/fdem-tools" --help)
[ "$got" = "FDEM_BIN=$prefix/bin/fdem" ] || { echo "launcher: expected FDEM_BIN=$prefix/bin/fdem, got '$got'"; exit 1; }
echo "install ok"
