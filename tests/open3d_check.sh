#!/usr/bin/env bash
# What a user's tool reads from a scan folder (run inside scripts/netns-run): a short twin scan of
# the bunny (free rig, 4 views), then Open3D (Debian's python3-open3d; scripts/test installs it)
# loads its cloud, a frame, the mesh and a depth image with its intrinsics, and checks them against
# the true mesh (tests/open3d_check.py says what, with the figures).
set -euo pipefail
SRC=${PBNBV_SOURCE_DIR:?}; BIN=${PBNBV_BIN_DIR:?}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
if ! timeout 300 "$BIN/pbnbv" scan --object bunny --rig free --area full --views 4 --stop-rule off --no-log \
      --out "$out/scan" >"$out/scan.log" 2>&1; then
  tail -30 "$out/scan.log"; echo "FAIL: the scan failed"; exit 1
fi
timeout 300 /usr/bin/python3 "$SRC/tests/open3d_check.py" "$out/scan"
