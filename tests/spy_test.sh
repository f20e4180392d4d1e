#!/usr/bin/env bash
# `pbnbv spy` starts lcm-spy (under a virtual display) with the project's message jar: it must
# discover every type in lcmtypes/, so every channel decodes.
set -euo pipefail
SRC=${PBNBV_SOURCE_DIR:?}; BIN=${PBNBV_BIN_DIR:?}
expected=$(ls "$SRC"/lcmtypes/*.lcm | wc -l)
log=$(mktemp)
# lcm-spy runs until it is stopped: stopped (as the timeout stops it) 2 s after it has listed the
# types it found, for errors to show, or after 20 s. It used to run the whole 20 s; it lists the
# types in a few seconds.
timeout 20 xvfb-run -a "$BIN/pbnbv" spy >"$log" 2>&1 &
spy=$!
for _ in $(seq 200); do
  grep -q "Found [0-9]* LCM types" "$log" && { sleep 2; break; }
  kill -0 "$spy" 2>/dev/null || break
  sleep 0.1
done
kill "$spy" 2>/dev/null || true
wait "$spy" || true
if grep -q "Found $expected LCM types" "$log"; then
  echo "lcm-spy found all $expected pbnbv types"
else
  echo "lcm-spy did not find the $expected pbnbv types; its output:"; cat "$log"; exit 1
fi
if grep -q "NoClassDefFoundError\|Exception" "$log"; then
  echo "lcm-spy reported errors:"; cat "$log"; exit 1
fi
