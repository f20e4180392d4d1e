#!/usr/bin/env bash
# `cmake --install` into a temporary prefix P, then run from there: P/bin holds pbnbv and its ten
# services (and no test), P/share/pbnbv the rig models, meshes, message jar and pbnbv view's page; the installed
# `pbnbv --help` works, and a one-view scan of the bunny finds its services beside it and its
# rig model and mesh in P/share/pbnbv (settings.json names them), from a folder outside the tree;
# the driver skeleton builds against the installed CMake package and passes rig-check --passive.
# KEEP_INSTALL=1 keeps P to look at.
set -euo pipefail
BIN=${PBNBV_BIN_DIR:?}
BUILD=$(dirname "$BIN")
P=$(mktemp -d /tmp/pbnbv-install-XXXXXX)
trap '[ -n "${KEEP_INSTALL:-}" ] || rm -rf "$P"' EXIT
fail() { echo "install test: $*" >&2; exit 1; }

cmake --install "$BUILD" --prefix "$P" >/dev/null
for f in pbnbv pbnbv-twin pbnbv-motion pbnbv-camera pbnbv-registration pbnbv-mapping pbnbv-coordinator \
         pbnbv-ellipsoids pbnbv-scorer pbnbv-replay-rig pbnbv-view; do
  [ -x "$P/bin/$f" ] || fail "$P/bin/$f is missing"
done
[ "$(ls "$P/bin" | wc -l)" = 11 ] || fail "P/bin holds more than pbnbv and its services: $(ls "$P/bin" | tr '\n' ' ')"
for f in models/rig_free.xml models/rig_arm.xml data/meshes/bunny.obj pbnbv_lcmtypes.jar web/index.html \
         web/three/three.module.js; do
  [ -f "$P/share/pbnbv/$f" ] || fail "$P/share/pbnbv/$f is missing"
done

help=$(cd / && "$P/bin/pbnbv" --help)
grep -q "scan" <<<"$help" || fail "pbnbv --help does not list the scan command: $help"

out="$P/scan"
if ! (cd / && timeout 240 "$P/bin/pbnbv" scan --object bunny --planner ring --views 1 --sim-speed 20 --no-log \
        --out "$out" >"$P/scan.log" 2>&1); then
  cat "$P/scan.log"; fail "the installed pbnbv's one-view scan failed"
fi
grep -q "\"$P/share/pbnbv/models/rig_" "$out/settings.json" || fail "settings.json does not name the installed rig model"
grep -q "\"$P/share/pbnbv/data/meshes/bunny.obj\"" "$out/settings.json" || fail "settings.json does not name the installed mesh"
grep -q '"state": "done"' "$out/scan.json" || fail "the scan did not finish: $(grep -A3 '"status"' "$out/scan.json")"
# The driver library as a package: the README's driver skeleton, built as a project of its own
# against P (find_package(pbnbv), pbnbv::driver), passes the installed rig-check's passive checks.
SRC=${PBNBV_SOURCE_DIR:?}
[ -f "$P/lib/cmake/pbnbv/pbnbv-config.cmake" ] || fail "P/lib/cmake/pbnbv/pbnbv-config.cmake is missing"
[ -f "$P/share/pbnbv/lcmtypes/arm_status_t.lcm" ] || fail "P/share/pbnbv/lcmtypes holds no message definitions"
if ! cmake -S "$SRC/examples/driver_skeleton" -B "$P/driver-build" -DCMAKE_PREFIX_PATH="$P" >"$P/driver.log" 2>&1 ||
   ! cmake --build "$P/driver-build" -j2 >>"$P/driver.log" 2>&1; then
  tail -n 30 "$P/driver.log"; fail "the driver skeleton does not build against the installed package"
fi
"$P/driver-build/my-rig-driver" >"$P/driver-run.log" 2>&1 &
driver=$!
if ! (cd / && timeout 60 "$P/bin/pbnbv" rig-check --passive --rig-model "$P/share/pbnbv/models/rig_arm.xml" \
        >"$P/rig-check.log" 2>&1); then
  kill "$driver" 2>/dev/null || true
  cat "$P/rig-check.log"; tail -n 20 "$P/driver-run.log"; fail "the installed driver skeleton fails rig-check --passive"
fi
kill "$driver"
wait "$driver" || true
echo "installed into $P: pbnbv --help and a one-view scan ran from there; a driver built against the package passed rig-check --passive"
