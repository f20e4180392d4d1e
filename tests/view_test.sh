#!/usr/bin/env bash
# `pbnbv view` in headless Chromium (run inside scripts/netns-run: the scan, the view and the
# browser share a private loopback; the browser is driven by tests/view_screenshot.py). Live: a short twin scan (sphere, free rig, 200 candidates)
# with `pbnbv view` following it; once a plan has come, /api/scene must hold cloud points with
# their normals, the plan's 200 candidates, a chosen view and the ground; a plain
# `chromium --headless --screenshot` (no driver, no waiting: it shoots at the load event) must
# show the scene, and the driven page's screenshot too: the cloud shaded (many levels of its
# colour), the chosen view's colour and the ground grid, with the side column beside the canvas,
# not over it. Then `pbnbv view DIR` on the finished folder, its cloud.ply given a colour per
# point: one scene per view taken, the same counts, the cloud drawn in that colour, shaded.
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
# Chromium through chromedriver, software WebGL, 1280 x 800; at most 120 s), and with LAYOUT_JSON
# what the page reports of its layout there.
screenshot() {  # URL PNG [LAYOUT_JSON]
  timeout -k 5 150 "$PY" "$SRC/tests/view_screenshot.py" "$1" "$2" 120 ${3:+"$3"} || fail "no screenshot of $1"
}

# A plain headless screenshot of URL into PNG: the command a user would type (as root, Chromium
# needs --no-sandbox), without a driver or --virtual-time-budget: it is taken at the load event,
# so the page must have drawn its scene by then.
plain_screenshot() {  # URL PNG
  HOME="$tmp" timeout -k 5 90 chromium --headless --no-sandbox --screenshot="$2" --window-size=1280,800 "$1" \
    >"$tmp/chromium.out" 2>&1 || { tail -5 "$tmp/chromium.out"; fail "chromium --headless --screenshot of $1 failed"; }
  [ -s "$2" ] || fail "chromium --headless --screenshot of $1 wrote no $2"
}

# What a screenshot shows in the 3-D scene: the window but the side column (the right 300 px,
# index.html). The cloud's pixels: the base colour R,G,B scaled by one light level (each channel
# within 6 + 4 % of the brightest), at least MIN_CLOUD of them in at least MIN_SHADES levels (the
# old flat, unlit cloud had one); at least MIN_CHOSEN of the chosen view's #ff00ff (within 12);
# at least 3000 of the grid's lines (#343434, #5a5a5a, within 3); and, with NOT_BASE, fewer than
# 30 pixels of that other base colour (a cloud drawn in its own colours has no cyan left).
check_scene() {  # PNG R,G,B MIN_CLOUD MIN_SHADES MIN_CHOSEN [NOT_R,G,B]
  "$PY" - "$@" <<'PY' || fail "screenshot $1 does not show the scene: the shaded cloud, the chosen view and the grid"
import sys, cv2, numpy as np
img = cv2.imread(sys.argv[1])
if img is None: sys.exit("cannot read " + sys.argv[1])
img = img[:, :img.shape[1] - 300, ::-1].astype(int)  # the scene, RGB
rgb = lambda t: np.array([int(x) for x in t.split(",")])
def cloud(base):
    top = int(np.argmax(base))
    level = img[..., top] / base[top]
    near = np.all(np.abs(img - level[..., None] * base) <= 6 + 0.04 * img[..., top:top + 1], axis=2) & (img[..., top] >= 40)
    return int(near.sum()), len(np.unique(img[..., top][near]))
near = lambda c, tol: int(np.all(np.abs(img - np.array(c)) <= tol, axis=2).sum())
n, shades = cloud(rgb(sys.argv[2]))
chosen = near((255, 0, 255), 12)
grid = near((0x34,) * 3, 3) + near((0x5a,) * 3, 3)
print(f"{sys.argv[1]}: {n} cloud pixels (need {sys.argv[3]}) in {shades} shades (need {sys.argv[4]}), "
      f"{chosen} chosen-view pixels (need {sys.argv[5]}), {grid} grid pixels (need 3000)")
ok = n >= int(sys.argv[3]) and shades >= int(sys.argv[4]) and chosen >= int(sys.argv[5]) and grid >= 3000
if len(sys.argv) > 6:
    other = cloud(rgb(sys.argv[6]))[0]
    print(f"  {other} pixels of {sys.argv[6]} (need fewer than 30)")
    ok = ok and other < 30
sys.exit(0 if ok else 1)
PY
}

# The driven page's layout (view_screenshot.py's LAYOUT_JSON) against the scene served (SCENE_JSON):
# the side column and the canvas do not overlap, the info panel is in the side column, the canvas
# takes at least half the width and the whole height; the grid has 10 cm cells on the scene's
# ground and its legend says so; the cloud has its normals, and its colours iff COLOURED (0/1).
check_layout() {  # LAYOUT_JSON SCENE_JSON COLOURED
  "$PY" - "$@" <<'PY' || fail "the page's layout or grid ($1)"
import json, sys
l, s, coloured = json.load(open(sys.argv[1])), json.load(open(sys.argv[2])), sys.argv[3] == "1"
c, side, info, w, v = l["canvas"], l["side"], l["info"], l["window"], l["view"]
print(f"layout: canvas {c}, side {side}, info {info}, window {w}; grid {v and v['grid']}; cloud {v and v['cloud']}")
area = lambda a, b: max(0, min(a["right"], b["right"]) - max(a["left"], b["left"])) * \
                   max(0, min(a["bottom"], b["bottom"]) - max(a["top"], b["top"]))
assert info and area(c, info) == 0, f"the info panel covers {info and area(c, info)} px² of the canvas"
assert side and v, "no side column, or no window.pbnbvView"
assert area(c, side) == 0, f"the side column covers {area(c, side)} px² of the canvas"
assert side["left"] <= info["left"] and info["right"] <= side["right"], "the info panel is not in the side column"
assert c["right"] - c["left"] >= 0.5 * w["width"] and c["bottom"] - c["top"] >= w["height"] - 1, "the canvas is too small"
g = v["grid"]
assert g and g["cell_m"] == 0.1 and g["lines"] >= 10, "no 10 cm grid"
assert s["ground"] is not None and abs(g["z_m"] - s["ground"]["z_m"]) < 1e-6, "the grid is not on the scene's ground"
assert "10 cm" in (l["scale_text"] or ""), "the legend does not give the grid's cell"
assert v["cloud"]["normals"] and v["cloud"]["colours"] == coloured, "the cloud's normals or colours are not drawn"
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
import json, math, sys
j = json.load(open(sys.argv[1])); n = int(sys.argv[2])
print(f"live view {j['view']}: {j['cloud_points']} cloud points drawn of {j['cloud_points_total']}, "
      f"{len(j['candidates'])} candidates (plan: {j['plan_candidates']}), {len(j['ellipsoids'])} ellipsoids, "
      f"{j['frontier_voxels']} frontier voxels, {len(j['views_taken'])} views taken")
ok = j['cloud_points'] > 0 and len(j['cloud']) == 3 * j['cloud_points'] and len(j['candidates']) == n \
     and j['plan_candidates'] == n and len(j['views_taken']) == j['view'] and len(j['ellipsoids']) >= 1
# The cloud's normals (fitted to each view's points live): one per point, nearly all found, unit
# (127); no colours; the grid's ground (the free rig: the working volume's floor) below the cloud.
nn = j['cloud_normals']
found = sum(1 for i in range(0, len(nn), 3) if 120 <= math.hypot(*nn[i:i + 3]) <= 134)
g = j['ground']
print(f"normals: {found} of {j['cloud_points']} points; colours: {len(j['cloud_colours'])}; ground {g}")
ok = ok and len(nn) == 3 * j['cloud_points'] and found >= 0.9 * j['cloud_points'] and j['cloud_colours'] == [] \
     and g is not None and 'free rig' in g['what'] and min(j['cloud'][2::3]) >= g['z_m']
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
# The plain headless screenshot first (the page draws before its load event), then the driven one.
t0=$(date +%s)
plain_screenshot "http://127.0.0.1:$PORT/?view=$view" "$tmp/plain.png"
echo "plain chromium --headless --screenshot: $(( $(date +%s) - t0 )) s"
check_scene "$tmp/plain.png" 0,200,255 300 20 50
screenshot "http://127.0.0.1:$PORT/?view=$view" "$tmp/live.png" "$tmp/live-layout.json"
check_scene "$tmp/live.png" 0,200,255 300 20 50
check_layout "$tmp/live-layout.json" "$tmp/live.json" 0
if [ -n "${PBNBV_VIEW_SCREENSHOT:-}" ]; then cp "$tmp/live.png" "$PBNBV_VIEW_SCREENSHOT"; fi

deadline=$(( $(date +%s) + 300 ))
while kill -0 $scan_pid 2>/dev/null; do
  [ "$(date +%s)" -lt "$deadline" ] || fail "the scan did not end within 300 s"
  sleep 1
done
wait $scan_pid || fail "the scan failed"
kill "${pids[0]}"; wait "${pids[0]}" 2>/dev/null || true

# --- a finished scan folder, its cloud.ply's colours (the twin's camera sends colour: the object's
# own, shaded) all made the same green, which the page must draw
"$PY" - "$tmp/scan/cloud.ply" <<'PY' || fail "cannot colour cloud.ply"
import sys, numpy as np
path = sys.argv[1]
d = open(path, "rb").read()
end = d.index(b"end_header\n") + len(b"end_header\n")
head = d[:end].decode().split("\n")
n = int(next(l for l in head if l.startswith("element vertex")).split()[2])
assert "format binary_little_endian 1.0" in head and head[-3] == "property uchar blue", head
assert head[-6] == "property float nz", head
rec = np.frombuffer(d[end:end + 27 * n], dtype=[("xyz_n", "<f4", 6), ("rgb", "u1", 3)]).copy()
assert len(set(map(tuple, rec["rgb"][:1000]))) > 1, "the twin's colours are shaded, not one colour"
rec["rgb"] = (60, 220, 0)
open(path, "wb").write(d[:end] + rec.tobytes())
PY
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
# Views count from 1: a folder has no view 0, and a view that is no view number is a 400.
curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$PORT/api/scene?view=0" | grep -q 404 || fail "view 0 of a folder is not a 404"
curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$PORT/api/scene?view=-2" | grep -q 400 || fail "view -2 is not a 400"
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
# The cloud's colours and normals from cloud.ply; the grid's ground; a scene not changed since the
# revision the page shows is answered 204; the page carries its first scene.
curl -sf --max-time 10 "http://127.0.0.1:$PORT/api/scene?view=1" -o "$tmp/dir.json" || fail "no scene of view 1"
"$PY" - "$tmp/dir.json" <<'PY' || fail "view 1 of the folder: not cloud.ply's colours and normals, or no ground"
import json, math, sys
j = json.load(open(sys.argv[1])); n = j["cloud_points"]; c = j["cloud_colours"]; nn = j["cloud_normals"]
found = sum(1 for i in range(0, len(nn), 3) if 120 <= math.hypot(*nn[i:i + 3]) <= 134)
print(f"folder view 1: {n} points, {len(c) // 3} colours, {found} normals, ground {j['ground']}")
sys.exit(0 if c == [60, 220, 0] * n and len(nn) == 3 * n and found >= 0.9 * n and j["ground"] is not None else 1)
PY
rev=$("$PY" -c "import json; print(json.load(open('$tmp/dir.json'))['revision'])")
code=$(curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$PORT/api/scene?view=1&since=$rev")
[ "$code" = 204 ] || fail "an unchanged scene (since=$rev) was answered $code, not 204"
curl -sf --max-time 10 "http://127.0.0.1:$PORT/?view=1" | "$PY" -c "
import json, re, sys
m = re.search(r'<script type=\"application/json\" id=\"initial\">(.*?)</script>', sys.stdin.read(), re.S)
j = json.loads(m.group(1)); sys.exit(0 if j['scene']['view'] == 1 and j['scene']['cloud_points'] > 0 else 1)" \
  || fail "the page of view 1 does not carry its scene"
screenshot "http://127.0.0.1:$PORT/?view=1" "$tmp/dir.png" "$tmp/dir-layout.json"
check_scene "$tmp/dir.png" 60,220,0 300 20 50 0,200,255
check_layout "$tmp/dir-layout.json" "$tmp/dir.json" 1
echo "pbnbv view: live and folder scenes drawn ($taken views)"
