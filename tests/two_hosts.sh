#!/usr/bin/env bash
# Two "hosts" on one machine: network namespaces joined by a veth pair, multicast with ttl=1 across
# the link, as a rig computer and a compute machine on one switch would be.
#   rig host:     the twin (as the rig's drivers) and `pbnbv rig-host` (motion executor, camera)
#   compute host: `pbnbv scan --external-rig --rig-host` (registration, mapping, ellipsoids,
#                 scorer, coordinator, lcm-logger)
# Usage: two_hosts.sh OUT RIG_MODEL TWIN_OPTIONS SCAN_OPTIONS   (needs root: ip netns)
set -euo pipefail
OUT=$1; RIG_MODEL=$2; TWIN_OPTIONS=$3; SCAN_OPTIONS=$4
BIN=${PBNBV_BIN_DIR:?}
ID=$$
RIG=pbnbv-rig-$ID; COMPUTE=pbnbv-compute-$ID
cleanup() {
  ip netns pids "$RIG" 2>/dev/null | xargs -r kill 2>/dev/null || true
  ip netns pids "$COMPUTE" 2>/dev/null | xargs -r kill 2>/dev/null || true
  sleep 0.5
  ip netns del "$RIG" 2>/dev/null || true
  ip netns del "$COMPUTE" 2>/dev/null || true
}
trap cleanup EXIT
ip netns add "$RIG"
ip netns add "$COMPUTE"
ip link add "vr$ID" type veth peer name "vc$ID"
ip link set "vr$ID" netns "$RIG"
ip link set "vc$ID" netns "$COMPUTE"
host() {  # host NS DEVICE ADDRESS
  ip -n "$1" link set lo up
  ip -n "$1" addr add "$3/24" dev "$2"
  ip -n "$1" link set "$2" up multicast on
  ip -n "$1" route add 224.0.0.0/4 dev "$2"
}
host "$RIG" "vr$ID" 10.77.0.1
host "$COMPUTE" "vc$ID" 10.77.0.2
export LCM_DEFAULT_URL="udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608"
mkdir -p "$OUT/rig-host"
# shellcheck disable=SC2086
ip netns exec "$RIG" "$BIN/pbnbv-twin" --speed 20 --model "$RIG_MODEL" $TWIN_OPTIONS --model-out "$OUT/rig-host/twin_model.xml" \
  >"$OUT/rig-host/twin.log" 2>&1 &
ip netns exec "$RIG" "$BIN/pbnbv" rig-host --rig-model "$RIG_MODEL" --logs "$OUT/rig-host" >"$OUT/rig-host/rig-host.log" 2>&1 &
# shellcheck disable=SC2086
ip netns exec "$COMPUTE" "$BIN/pbnbv" scan --external-rig --rig-host $SCAN_OPTIONS --out "$OUT/scan"
