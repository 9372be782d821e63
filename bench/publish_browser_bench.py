"""A published site as a visitor's browser sees it: Debian's chromium, headless, software WebGL2
(SwiftShader), the site served by python3 -m http.server on 127.0.0.1. Per site, unthrottled and
at 20 Mbit/s (DevTools' network emulation): seconds to the first image, to all data (or the
memory budget), to the converged image; bytes before the first image; the longest main-thread
task while data streams (PerformanceObserver "longtask": tasks over 50 ms; "< 50" when none);
points an ensemble draws (a GPU's published GL_POINTS rate gives its frame time from that;
software rasterisation says nothing of a GPU). Timings are printed, never asserted.

Usage: /usr/bin/python3 bench/publish_browser_bench.py CANDI ARCHIVE [ARCHIVE...] [-L 100]
       [--memory-mb 256] [--size 1024x768] [--work-dir DIR]
(`candi bench publish --keep` leaves archives in candi-bench-view/scene-N.archive.)
"""
import argparse
import json
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "browser"))
from devtools import Browser  # noqa: E402

LONGTASKS = """
window.__longest = 0;
new PerformanceObserver((list) => {
  for (const e of list.getEntries()) window.__longest = Math.max(window.__longest, e.duration);
}).observe({ type: 'longtask', buffered: true });
"""


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def measure(url, width, height, mbit):
    browser = Browser(width, height, webgl=True)
    try:
        browser.call("Page.addScriptToEvaluateOnNewDocument", source=LONGTASKS)
        browser.call("Network.enable")
        if mbit:
            rate = mbit * 1e6 / 8
            browser.call("Network.emulateNetworkConditions", offline=False, latency=20, downloadThroughput=rate,
                         uploadThroughput=rate)
        browser.call("Page.navigate", url=url)
        browser.wait_for("window.candiViewer && window.candiViewer.progress && window.candiViewer.progress().converged "
                         "&& window.candiViewer.progress().allLoadedAt !== null", 3600, "convergence")
        p = browser.evaluate("window.candiViewer.progress()")
        p["longest"] = browser.evaluate("window.__longest")
        p["webgl2"] = browser.evaluate("window.candiViewer.webgl2")
        return p
    finally:
        browser.close()


def main():
    a = argparse.ArgumentParser()
    a.add_argument("candi")
    a.add_argument("archives", nargs="+")
    a.add_argument("-L", type=int, default=100)
    a.add_argument("--memory-mb", type=int, default=256)
    a.add_argument("--size", default="1024x768")
    a.add_argument("--work-dir", default=None)
    args = a.parse_args()
    width, height = (int(v) for v in args.size.split("x"))
    work = args.work_dir or tempfile.mkdtemp(prefix="candi-publish-bench-")
    print("site in chromium (software WebGL2), %dx%d window, L = %d, page budget %d MB" %
          (width, height, args.L, args.memory_mb))
    print("%12s %9s %11s %9s %9s %10s %11s %12s %16s" % ("points", "network", "first MB", "first s", "data s",
          "converged", "held M pts", "longest ms", "points/ensemble"))
    for archive in args.archives:
        site = os.path.join(work, "site")
        r = subprocess.run([args.candi, "-q", "publish", archive, "-o", site, "-L", str(args.L)],
                           capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit(r.stderr)
        port = free_port()
        server = subprocess.Popen([sys.executable, "-m", "http.server", "-b", "127.0.0.1", "-d", site, str(port)],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(0.5)
        try:
            for mbit in (None, 20):
                p = measure("http://127.0.0.1:%d/?memory_mb=%d" % (port, args.memory_mb), width, height, mbit)
                with open(os.path.join(site, "site.json")) as f:
                    points = json.load(f)["scene"]["points"]
                print("%12d %9s %11.2f %9.2f %9.2f %10.2f %11.2f %12s %16d" % (
                    points, "%d Mbit/s" % mbit if mbit else "local", p["firstImageBytes"] / 1e6,
                    p["firstImageAt"] / 1000, p["allLoadedAt"] / 1000, p["convergedAt"] / 1000, p["heldPoints"] / 1e6,
                    "%.0f" % p["longest"] if p["longest"] else "< 50", points // args.L))
                sys.stdout.flush()
        finally:
            server.terminate()
            shutil.rmtree(site, ignore_errors=True)
    if not args.work_dir:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
