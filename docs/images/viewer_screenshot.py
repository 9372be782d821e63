#!/usr/bin/env python3
"""Screenshot of `candi view` for docs/images/viewer.png (see docs/images/README.md).

Run from the repository root with Debian's /usr/bin/python3 (it has python3-websocket) and
chromium installed:

    W=800 H=560 SETTINGS='{"repeat_level": 32, "layers": [3, 1, 1, 3]}' \
        /usr/bin/python3 docs/images/viewer_screenshot.py BUILD/archive viewer.png corner_transparent 255,192 470,206

Arguments: the folder to view, the PNG to write, a saved view to select, then canvas pixels to
measure at. SETTINGS (optional) is passed to the page's candiViewer.setSettings.
"""
import base64
import os
import re
import subprocess
import sys
import time

sys.path.insert(0, "tests/browser")
import devtools  # noqa: E402  (the browser tests' DevTools client)

build, out = sys.argv[1], sys.argv[2]
saved_view = sys.argv[3] if len(sys.argv) > 3 else ""
view = subprocess.Popen(["build/apps/candi", "view", build, "--port", "0"],
                        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
url = None
while url is None:
    line = view.stdout.readline()
    if not line:
        raise SystemExit("candi view exited")
    m = re.search(r"(http://\S+)", line)
    if m:
        url = m.group(1)
browser = devtools.Browser(int(os.environ.get("W", 1000)), int(os.environ.get("H", 620)))
converged = ("(() => { const f = candiViewer.stats.lastFrame; return f && f.converged && "
             "f.seq === candiViewer.stats.drawnSeq && f.seq === candiViewer.viewSeq() ? f : null; })()")
try:
    browser.call("Page.enable")
    browser.call("Page.navigate", url=url)
    browser.wait_for("window.candiViewer && candiViewer.stats.lastFrame !== null", 60, "a first frame")
    if saved_view:
        browser.evaluate("(() => { const s = document.getElementById('views'); s.value = '%s'; "
                         "s.dispatchEvent(new Event('change')); })()" % saved_view)
    if os.environ.get("SETTINGS"):
        time.sleep(0.5)
        browser.evaluate("candiViewer.setSettings(%s)" % os.environ["SETTINGS"])
    time.sleep(0.5)
    browser.wait_for(converged, 120, "convergence")
    for point in sys.argv[4:]:
        x, y = (float(v) for v in point.split(","))
        browser.evaluate("candiViewer.measureAt(%f, %f)" % (x, y), await_promise=True)
    time.sleep(1.0)
    shot = browser.call("Page.captureScreenshot", format="png")
    with open(out, "wb") as f:
        f.write(base64.b64decode(shot["data"]))
finally:
    browser.close()
    view.terminate()
    view.wait()
