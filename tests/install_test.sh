#!/usr/bin/env bash
# The Debian package (cpack -G DEB), unpacked into a scratch root R (dpkg-deb -x: no root, no
# container), then run from there (P = R/usr): P/bin holds pbnbv alone, P/libexec/pbnbv its ten
# services (and no test), P/share/pbnbv the rig models, meshes, message jar and pbnbv view's page
# (with three.js's licence), P/share/doc/pbnbv the licence, notices and changelog; the package
# depends on the libraries the programs link; the installed `pbnbv --help` works, and a 3-view scan
# of the bunny finds its services in P/libexec/pbnbv and its rig model and mesh in P/share/pbnbv
# (settings.json names them), from a folder outside the tree; the driver skeleton builds against
# the installed CMake package and passes rig-check --passive. KEEP_INSTALL=1 keeps R to look at.
set -euo pipefail
BIN=${PBNBV_BIN_DIR:?}
BUILD=$(dirname "$BIN")
T=$(mktemp -d /tmp/pbnbv-install-XXXXXX)
trap '[ -n "${KEEP_INSTALL:-}" ] || rm -rf "$T"' EXIT
fail() { echo "install test: $*" >&2; exit 1; }

R="$T/root"
# gzip rather than the release's xz: the same package, made in a fraction of the time.
(cd "$BUILD" && cpack -G DEB -D CPACK_DEBIAN_COMPRESSION_TYPE=gzip -B "$T/pkg" >"$T/cpack.log" 2>&1) \
  || { tail -20 "$T/cpack.log"; fail "cpack -G DEB failed"; }
deb=$(ls "$T"/pkg/pbnbv_*_amd64.deb 2>/dev/null | head -1)
[ -n "$deb" ] || fail "cpack made no pbnbv_*.deb: $(ls "$T/pkg")"
depends=$(dpkg-deb -f "$deb" Depends)
for lib in liblcm1 libmujoco2.2.2 liboctomap1.9 liblcm-bin; do
  grep -q "$lib" <<<"$depends" || fail "$deb does not depend on $lib: $depends"
done
dpkg-deb -x "$deb" "$R"
P="$R/usr"
# The user's programs: pbnbv and the UR arm driver (pbnbv-ur-driver).
[ "$(ls "$P/bin" | tr '\n' ' ')" = "pbnbv pbnbv-ur-driver " ] || fail "P/bin holds other than pbnbv and pbnbv-ur-driver: $(ls "$P/bin" | tr '\n' ' ')"
for f in pbnbv-twin pbnbv-motion pbnbv-camera pbnbv-registration pbnbv-mapping pbnbv-coordinator \
         pbnbv-ellipsoids pbnbv-scorer pbnbv-replay-rig pbnbv-view; do
  [ -x "$P/libexec/pbnbv/$f" ] || fail "$P/libexec/pbnbv/$f is missing"
done
[ "$(ls "$P/libexec/pbnbv" | wc -l)" = 10 ] || fail "P/libexec/pbnbv holds more than the services: $(ls "$P/libexec/pbnbv" | tr '\n' ' ')"
for f in models/rig_free.xml models/rig_arm.xml models/rig_ur5e.xml data/meshes/bunny.obj pbnbv_lcmtypes.jar \
         web/index.html web/three/three.module.js web/three/LICENSE; do
  [ -f "$P/share/pbnbv/$f" ] || fail "$P/share/pbnbv/$f is missing"
done
for f in LICENSE THIRD_PARTY.md CHANGELOG.md; do
  [ -f "$P/share/doc/pbnbv/$f" ] || fail "$P/share/doc/pbnbv/$f is missing"
done

help=$(cd / && "$P/bin/pbnbv" --help)
grep -q "scan" <<<"$help" || fail "pbnbv --help does not list the scan command: $help"

out="$T/scan"
if ! (cd / && timeout 240 "$P/bin/pbnbv" scan --object bunny --views 3 --sim-speed 20 --no-log \
        --out "$out" >"$T/scan.log" 2>&1); then
  cat "$T/scan.log"; fail "the installed pbnbv's 3-view scan failed"
fi
grep -q "\"$P/libexec/pbnbv/pbnbv-twin\"" "$out/processes.json" || fail "processes.json does not run the installed services"
grep -q "\"$P/share/pbnbv/models/rig_" "$out/settings.json" || fail "settings.json does not name the installed rig model"
grep -q "\"$P/share/pbnbv/data/meshes/bunny.obj\"" "$out/settings.json" || fail "settings.json does not name the installed mesh"
grep -q '"state": "done"' "$out/scan.json" || fail "the scan did not finish: $(grep -A3 '"status"' "$out/scan.json")"
grep -q '"views_done": 3' "$out/scan.json" || fail "the scan did not take 3 views: $(grep -A5 '"status"' "$out/scan.json")"
# The driver library as a package: the driver contract's skeleton (docs/driver-contract.md), built as a project of its own
# against P (find_package(pbnbv), pbnbv::driver), passes the installed rig-check's passive checks.
SRC=${PBNBV_SOURCE_DIR:?}
[ -f "$P/lib/cmake/pbnbv/pbnbv-config.cmake" ] || fail "P/lib/cmake/pbnbv/pbnbv-config.cmake is missing"
[ -f "$P/share/pbnbv/lcmtypes/arm_status_t.lcm" ] || fail "P/share/pbnbv/lcmtypes holds no message definitions"
if ! cmake -S "$SRC/examples/driver_skeleton" -B "$T/driver-build" -DCMAKE_PREFIX_PATH="$P" >"$T/driver.log" 2>&1 ||
   ! cmake --build "$T/driver-build" -j2 >>"$T/driver.log" 2>&1; then
  tail -n 30 "$T/driver.log"; fail "the driver skeleton does not build against the installed package"
fi
"$T/driver-build/my-rig-driver" >"$T/driver-run.log" 2>&1 &
driver=$!
if ! (cd / && timeout 60 "$P/bin/pbnbv" rig-check --passive --rig-model "$P/share/pbnbv/models/rig_arm.xml" \
        >"$T/rig-check.log" 2>&1); then
  kill "$driver" 2>/dev/null || true
  cat "$T/rig-check.log"; tail -n 20 "$T/driver-run.log"; fail "the installed driver skeleton fails rig-check --passive"
fi
kill "$driver"
wait "$driver" || true
echo "$(basename "$deb") unpacked into $R: pbnbv --help and a 3-view scan ran from there; a driver built against the package passed rig-check --passive"
