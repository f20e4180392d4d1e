#!/usr/bin/env bash
# `pbnbv view` in headless Chromium (run inside scripts/netns-run: the scan, the view and the
# browser share a private loopback; the browser is driven by tests/view_screenshot.py). Live: a short twin scan (sphere, free rig, 200 candidates)
# with `pbnbv view` following it; once a plan has come, /api/scene must hold cloud points, the
# plan's 200 candidates and a chosen view, and the page's screenshot must show the cloud's colour
# over an area and the chosen view's marker colour. Then `pbnbv view DIR` on the finished folder:
# one scene per view taken, the same counts, and the same two colours in its screenshot.
set -euo pipefail
SRC=${PBNBV_SOURCE_DIR:?}; BIN=${PBNBV_BIN_DIR:?}
PY=/usr/bin/python3   # Debian's, with python3-opencv (scripts/test installs it)
tmp=$(mktemp -d)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$tmp"/*.log; do echo "--- $f"; tail -20 "$f"; done; exit 1; }
CANDIDATES=200

# Waits (deadline in s) until the command succeeds.
wait_for() {
  local deadline=$(( $(date +%s) + $1 )); shift
  until "$@" >/dev/null 2>&1; do
    [ "$(date +%s)" -lt "$deadline" ] || return 1
    sleep 0.5
  done
}

# The JSON of URL, checked by a Python expression on `j` (exit 1 when false).
json_check() {  # URL EXPR
  curl -sf --max-time 5 "$1" | "$PY" -c "import json,sys; j=json.load(sys.stdin); sys.exit(0 if ($2) else 1)"
}

# Screenshot of URL into PNG once the page has drawn its scene (view_screenshot.py: headless
# Chromium through chromedriver, software WebGL; at most 120 s).
screenshot() {  # URL PNG
  timeout -k 5 150 "$PY" "$SRC/tests/view_screenshot.py" "$1" "$2" 120 || fail "no screenshot of $1"
}

# Pixels of the cloud's colour (#00c8ff) and of the chosen view's (#ff00ff), each within 12 per
# channel, above the legend (the bottom 60 rows, whose swatches have the same colours); at least
# MIN_CLOUD and MIN_CHOSEN of them.
check_pixels() {  # PNG MIN_CLOUD MIN_CHOSEN
  "$PY" - "$@" <<'PY' || fail "screenshot $1 does not show the cloud and the chosen view"
import sys, cv2, numpy as np
img = cv2.imread(sys.argv[1])  # BGR
if img is None: sys.exit("cannot read " + sys.argv[1])
img = img[:-60]
def count(bgr): return int(np.all(np.abs(img.astype(int) - np.array(bgr)) <= 12, axis=2).sum())
cloud, chosen = count((255, 200, 0)), count((255, 0, 255))
print(f"{sys.argv[1]}: {cloud} cloud pixels (need {sys.argv[2]}), {chosen} chosen-view pixels (need {sys.argv[3]})")
sys.exit(0 if cloud >= int(sys.argv[2]) and chosen >= int(sys.argv[3]) else 1)
PY
}

# --- live
PORT=8765
"$BIN/pbnbv" view --port $PORT >"$tmp/view.log" 2>&1 &
pids+=($!)
wait_for 20 curl -sf --max-time 2 "http://127.0.0.1:$PORT/api/views" || fail "pbnbv view did not answer within 20 s"
"$BIN/pbnbv" scan --object sphere --rig free --area full --views 4 --candidates $CANDIDATES --stop-rule off \
  --sim-speed 20 --no-log --out "$tmp/scan" >"$tmp/scan.log" 2>&1 &
scan_pid=$!
pids+=($scan_pid)
# The newest scene with a cloud and a plan (the scan may be past it: a view's scene is kept as it
# was, and the last view has no plan after it), saved as live.json.
live_scene_with_plan() {
  "$PY" - "http://127.0.0.1:$PORT" "$tmp/live.json" <<'PY'
import json, sys, urllib.request
base, out = sys.argv[1], sys.argv[2]
get = lambda path: json.load(urllib.request.urlopen(base + path, timeout=5))
for v in reversed(get("/api/views")["views"]):
    j = get(f"/api/scene?view={v}")
    if j["view"] >= 1 and j["chosen"] is not None and len(j["candidates"]) > 0 and j["cloud_points"] > 0:
        json.dump(j, open(out, "w"))
        sys.exit(0)
sys.exit(1)
PY
}
wait_for 300 live_scene_with_plan || fail "no scene with a cloud and a plan within 300 s"
view=$("$PY" -c "import json; print(json.load(open('$tmp/live.json'))['view'])")
"$PY" - "$tmp/live.json" $CANDIDATES <<'PY' || fail "live scene counts"
import json, sys
j = json.load(open(sys.argv[1])); n = int(sys.argv[2])
print(f"live view {j['view']}: {j['cloud_points']} cloud points drawn of {j['cloud_points_total']}, "
      f"{len(j['candidates'])} candidates (plan: {j['plan_candidates']}), {len(j['ellipsoids'])} ellipsoids, "
      f"{j['frontier_voxels']} frontier voxels, {len(j['views_taken'])} views taken")
ok = j['cloud_points'] > 0 and len(j['cloud']) == 3 * j['cloud_points'] and len(j['candidates']) == n \
     and j['plan_candidates'] == n and len(j['views_taken']) == j['view'] and len(j['ellipsoids']) >= 1
# The page's F, computed again from the plan's request, map and ellipsoids, is the plan's F at
# the chosen view (one of the candidates).
import math
c = j['chosen']['position_m']
near = min(j['candidates'], key=lambda k: math.dist(k['pose']['position_m'], c))
print(f"chosen view: plan F {j['chosen_quality_px']:.3f} px, the page's F there {near['quality_px']:.3f} px "
      f"({math.dist(near['pose']['position_m'], c):.2e} m away)")
# pbnbv ranks by its combined score (VIEW_PLAN's ranking "combined": F, the gap to the views taken
# and rays through the map, each scaled to [0, 1], so 0 to 3) or, with nothing left to aim at, by
# the angle to the nearest view taken ("gap_deg"): there the page's F is not the plan's figure,
# and the pose and the score's range are checked. pbnbv-paper's plans rank by F ("f_px").
assert j['chosen_ranking'] in ('f_px', 'gap_deg', 'combined'), j['chosen_ranking']
if j['chosen_ranking'] == 'f_px':
    ok = ok and abs(near['quality_px'] - j['chosen_quality_px']) <= 1e-6 * max(1.0, abs(j['chosen_quality_px']))
elif j['chosen_ranking'] == 'combined':
    ok = ok and 0 <= j['chosen_quality_px'] <= 3
ok = ok and math.dist(near['pose']['position_m'], c) < 1e-6
sys.exit(0 if ok else 1)
PY
# The scene of that view stays as it was once the scan moves on (the latest may have no plan yet).
screenshot "http://127.0.0.1:$PORT/?view=$view" "$tmp/live.png"
check_pixels "$tmp/live.png" 300 50
if [ -n "${PBNBV_VIEW_SCREENSHOT:-}" ]; then cp "$tmp/live.png" "$PBNBV_VIEW_SCREENSHOT"; fi

deadline=$(( $(date +%s) + 300 ))
while kill -0 $scan_pid 2>/dev/null; do
  [ "$(date +%s)" -lt "$deadline" ] || fail "the scan did not end within 300 s"
  sleep 1
done
wait $scan_pid || fail "the scan failed"
kill "${pids[0]}"; wait "${pids[0]}" 2>/dev/null || true

# --- a finished scan folder
PORT=8766
"$BIN/pbnbv" view "$tmp/scan" --port $PORT >"$tmp/view-dir.log" 2>&1 &
pids+=($!)
wait_for 60 curl -sf --max-time 2 "http://127.0.0.1:$PORT/api/views" || fail "pbnbv view DIR did not answer within 60 s"
taken=$("$PY" -c "import json; print(sum('capture' in v for v in json.load(open('$tmp/scan/scan.json'))['views']))")
json_check "http://127.0.0.1:$PORT/api/views" "j['views'] == list(range(1, $taken + 1)) and not j['live']" \
  || fail "/api/views of the folder is not views 1..$taken"
json_check "http://127.0.0.1:$PORT/api/scene?view=1" \
  "j['cloud_points'] > 0 and len(j['candidates']) == $CANDIDATES and j['chosen'] is not None and len(j['views_taken']) == 1" \
  || fail "view 1 of the folder: no cloud, not $CANDIDATES candidates or no chosen view"
json_check "http://127.0.0.1:$PORT/api/scene?view=$taken" "len(j['views_taken']) == $taken and j['chosen'] is None" \
  || fail "the last view of the folder: not $taken views taken, or a plan after the last view"
curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$PORT/api/scene?view=99" | grep -q 404 || fail "view 99 is not a 404"
# Hostile clients: another site's Host (DNS rebinding) is refused; a 4 MB body is refused before
# it is buffered (the server's memory stays within 16 MB of before); twenty connections that send
# nothing leave the page answering.
code=$(curl -s -o /dev/null -w '%{http_code}' -H "Host: evil.example:$PORT" "http://127.0.0.1:$PORT/api/views")
[ "$code" = 403 ] || fail "Host evil.example was answered $code, not 403"
curl -sf -o /dev/null -H "Host: localhost:$PORT" "http://127.0.0.1:$PORT/api/views" || fail "Host localhost was refused"
view_pid=${pids[-1]}
rss() { awk '/^VmRSS/ {print $2}' "/proc/$view_pid/status"; }
before=$(rss)
code=$(head -c 4000000 /dev/zero | curl -s -o /dev/null -w '%{http_code}' --max-time 10 -X POST --data-binary @- \
  "http://127.0.0.1:$PORT/api/views")
[ "$code" = 413 ] || fail "a 4 MB body was answered $code, not 413"
after=$(rss)
[ $((after - before)) -lt 16384 ] || fail "a 4 MB body grew the view from $before kB to $after kB"
"$PY" - "$PORT" <<'PYEOF' || fail "twenty idle connections starved the page"
import socket, sys, time, urllib.request
port = int(sys.argv[1])
idle = [socket.create_connection(("127.0.0.1", port)) for _ in range(20)]
for s in idle:
    s.send(b"GET /api/views HTTP/1.1\r\n")  # and never the rest
t0 = time.time()
with urllib.request.urlopen(f"http://127.0.0.1:{port}/api/views", timeout=3) as r:
    assert r.status == 200
print(f"pbnbv view: answered in {time.time() - t0:.2f} s beside 20 idle connections")
PYEOF
screenshot "http://127.0.0.1:$PORT/?view=1" "$tmp/dir.png"
check_pixels "$tmp/dir.png" 300 50
echo "pbnbv view: live and folder scenes drawn ($taken views)"
