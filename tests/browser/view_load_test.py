"""A bounded load test of candi view's server on 127.0.0.1: 8 pages orbiting for 30 s (and one
that never reads its socket), each sending a camera every 50 ms.

Usage: view_load_test.py CANDI SOURCE_DIR   (CANDI_VIEW_LOAD_SECONDS overrides the 30 s)

Checks: the server never crashes and still answers afterwards; every orbiting page keeps
receiving frames in every third of the run (the page that does not read does not hold them up);
the server's resident memory at the end is within 64 MB of what it was after the first third
(no leak). Frame rates are printed, not asserted.
"""
import json
import os
import sys
import threading
import time
import math

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import websocket  # noqa: E402  python3-websocket

from view_browser_test import Viewer, run, script_main  # noqa: E402
import view_browser_test  # noqa: E402


def rss_mb(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return 0.0


def check(work):
    seconds = float(os.environ.get("CANDI_VIEW_LOAD_SECONDS", "30"))
    ply = os.path.join(work, "foundation.ply")
    run("foundation", os.path.join(view_browser_test.SOURCE, "examples", "borobudur", "foundation.dxf"), "-o", ply,
        "--count", "300000", "--no-self-intersection")
    archive = os.path.join(work, "a.archive")
    run("pack", ply, "-o", archive)
    viewer = Viewer(archive)
    first = viewer.scene()["first_view"]
    url = "ws://127.0.0.1:%d/ws?token=%s" % (viewer.port, viewer.token)
    thirds = 3
    frames = [[0] * thirds for _ in range(8)]
    errors = []
    start = time.time()
    stop = threading.Event()

    def camera(k, t):
        a = 0.6 * t + k
        tx, ty, tz = first["target"]
        ex, ey, ez = first["eye"]
        dx, dy = ex - tx, ey - ty
        c = dict(first, width=320, height=240)
        c["eye"] = [tx + math.cos(a) * dx - math.sin(a) * dy, ty + math.sin(a) * dx + math.cos(a) * dy, ez]
        return c

    def page(k):
        try:
            ws = websocket.create_connection(url, timeout=600)
        except Exception as e:  # noqa: BLE001
            errors.append("page %d: %s" % (k, e))
            return

        def reader():
            try:
                while not stop.is_set():
                    data = ws.recv()
                    if isinstance(data, bytes) and data:
                        third = min(thirds - 1, int((time.time() - start) / seconds * thirds))
                        frames[k][third] += 1
                    elif isinstance(data, str) and '"error"' in data:
                        errors.append("page %d: %s" % (k, data))
            except Exception as e:  # noqa: BLE001
                if not stop.is_set():
                    errors.append("page %d reader: %s" % (k, e))

        threading.Thread(target=reader, daemon=True).start()
        seq = 0
        while not stop.is_set():
            seq += 1
            ws.send(json.dumps({"type": "view", "seq": seq, "camera": camera(k, time.time() - start),
                                "settings": {"repeat_level": 50}}))
            time.sleep(0.05)
        ws.close()

    # A page that sends cameras and never reads: its socket fills and stays full.
    stalled = websocket.create_connection(url, timeout=600)
    stalled.sock.setsockopt(__import__("socket").SOL_SOCKET, __import__("socket").SO_RCVBUF, 4096)
    for s in range(50):
        stalled.send(json.dumps({"type": "view", "seq": s + 1, "camera": dict(first, width=1024, height=768),
                                 "settings": {"repeat_level": 100, "seed": s + 1}}))
    threads = [threading.Thread(target=page, args=(k,), daemon=True) for k in range(8)]
    for t in threads:
        t.start()
    time.sleep(seconds / thirds)
    rss_early = rss_mb(viewer.process.pid)
    time.sleep(seconds - seconds / thirds)
    rss_late = rss_mb(viewer.process.pid)
    stop.set()
    for t in threads:
        t.join(timeout=60)
    alive = viewer.process.poll() is None
    status, _ = viewer.request("GET", "/api/scene?token=" + viewer.token)
    stalled.close()
    viewer.close()
    print("frames per page and third of %.0f s: %s" % (seconds, frames))
    print("server RSS: %.0f MB after a third, %.0f MB at the end" % (rss_early, rss_late))
    failures = []
    if not alive:
        failures.append("the server died:\n" + viewer.stderr[-3000:])
    if status != 200:
        failures.append("the server does not answer after the load (%d)" % status)
    if errors:
        failures.append("errors: %s" % errors[:5])
    for k in range(8):
        if min(frames[k]) == 0:
            failures.append("page %d received no frame in some third: %s" % (k, frames[k]))
    if rss_late > rss_early + 64:
        failures.append("resident memory grew from %.0f to %.0f MB" % (rss_early, rss_late))
    return failures


if __name__ == "__main__":
    sys.exit(script_main(check, "candi-view-load-"))
