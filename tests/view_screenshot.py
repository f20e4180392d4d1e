#!/usr/bin/python3
"""Screenshot of a pbnbv view page once it has drawn its scene, in headless Chromium driven by
chromedriver over WebDriver's HTTP protocol (no client library needed).
  view_screenshot.py URL PNG DEADLINE_S [LAYOUT_JSON]
Starts chromedriver on a free loopback port, opens URL, waits (at most DEADLINE_S) until the page's
title ends with "drawn" (view.js sets it once the scene is on the canvas), saves the screenshot as
PNG, and ends the browser and chromedriver in every case. Exit 1 with the reason on failure.
With LAYOUT_JSON, also writes there what the page reports of its layout and drawing: the bounding
boxes of the canvas, the side column and the info panel, the window's size, the grid's legend text
and view.js's window.pbnbvView (the view, the cloud's look, the grid)."""
import base64, json, socket, subprocess, sys, time, urllib.request

url, png, deadline_s = sys.argv[1], sys.argv[2], float(sys.argv[3])
layout_json = sys.argv[4] if len(sys.argv) > 4 else None
LAYOUT_SCRIPT = """
const box = (e) => { if (!e) return null; const r = e.getBoundingClientRect();
                     return {left: r.left, top: r.top, right: r.right, bottom: r.bottom}; };
const scale = document.getElementById('scale');
return {canvas: box(document.querySelector('canvas')), side: box(document.getElementById('side')),
        info: box(document.getElementById('info')), window: {width: window.innerWidth, height: window.innerHeight},
        scale_text: scale ? scale.textContent : null, view: window.pbnbvView || null};
"""
deadline = time.monotonic() + deadline_s

with socket.socket() as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
base = f"http://127.0.0.1:{port}"


def call(method, path, body=None, timeout=30):
    data = None if body is None else json.dumps(body).encode()
    req = urllib.request.Request(base + path, data=data, method=method, headers={"Content-Type": "application/json"})
    with urllib.request.urlopen(req, timeout=timeout) as r:
        return json.load(r)["value"]


driver = subprocess.Popen(["chromedriver", f"--port={port}"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
session = None
try:
    while True:
        try:
            if call("GET", "/status", timeout=2).get("ready"):
                break
        except OSError:
            pass
        if time.monotonic() > deadline:
            sys.exit("chromedriver did not start")
        time.sleep(0.2)
    args = ["--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
            "--window-size=1280,800", "--hide-scrollbars", "--disable-dev-shm-usage"]
    session = call("POST", "/session", {"capabilities": {"alwaysMatch": {
        "browserName": "chrome", "goog:chromeOptions": {"binary": "/usr/bin/chromium", "args": args}}}}, timeout=60)["sessionId"]
    call("POST", f"/session/{session}/url", {"url": url}, timeout=60)
    title = ""
    while not title.endswith("drawn"):
        if time.monotonic() > deadline:
            sys.exit(f"the page did not draw its scene within {deadline_s:.0f} s (title '{title}')")
        time.sleep(0.5)
        title = call("GET", f"/session/{session}/title")
    with open(png, "wb") as f:
        f.write(base64.b64decode(call("GET", f"/session/{session}/screenshot", timeout=60)))
    if layout_json:
        with open(layout_json, "w") as f:
            json.dump(call("POST", f"/session/{session}/execute/sync", {"script": LAYOUT_SCRIPT, "args": []}), f)
    print(f"{url}: '{title}' -> {png}")
finally:
    if session:
        try:
            call("DELETE", f"/session/{session}", timeout=30)
        except OSError:
            pass
    driver.terminate()
    try:
        driver.wait(timeout=10)
    except subprocess.TimeoutExpired:
        driver.kill()
