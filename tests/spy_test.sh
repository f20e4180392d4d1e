#!/usr/bin/env bash
# `pbnbv spy` starts lcm-spy (under a virtual display) with the project's message jar: it must
# discover every type in lcmtypes/, so every channel decodes.
set -euo pipefail
SRC=${PBNBV_SOURCE_DIR:?}; BIN=${PBNBV_BIN_DIR:?}
expected=$(ls "$SRC"/lcmtypes/*.lcm | wc -l)
log=$(mktemp)
timeout 20 xvfb-run -a "$BIN/pbnbv" spy >"$log" 2>&1 || true   # runs until the timeout
if grep -q "Found $expected LCM types" "$log"; then
  echo "lcm-spy found all $expected pbnbv types"
else
  echo "lcm-spy did not find the $expected pbnbv types; its output:"; cat "$log"; exit 1
fi
if grep -q "NoClassDefFoundError\|Exception" "$log"; then
  echo "lcm-spy reported errors:"; cat "$log"; exit 1
fi
