"""candi view as a page sees it, over its WebSocket on 127.0.0.1: first-frame latency after each
camera change (p50/p95), frames/s while orbiting, seconds from a camera change to the converged
PNG. For comparing `candi view` in one process with `mpirun -np K candi view` (candi bench view
measures the renderer alone).

Usage: /usr/bin/python3 bench/view_client_bench.py CANDI ARCHIVE [--np K] [--threads T]
       [--frames 30] [--size 1024x768] [-L 100]
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import time
import urllib.request

import websocket  # python3-websocket


def main():
    p = argparse.ArgumentParser()
    p.add_argument("candi")
    p.add_argument("archive")
    p.add_argument("--np", type=int, default=1)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--frames", type=int, default=30)
    p.add_argument("--size", default="1024x768")
    p.add_argument("-L", type=int, default=100)
    a = p.parse_args()
    w, h = (int(v) for v in a.size.split("x"))
    cmd = [a.candi, "-q", "view", a.archive, "--port", "0", "--threads", str(a.threads)]
    if a.np > 1:
        cmd = ["mpirun", "--oversubscribe", "-np", str(a.np)] + (["--allow-run-as-root"] if os.geteuid() == 0 else []) + cmd
    server = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    url = server.stdout.readline().split(": ", 1)[1].strip()
    port, token = int(url.split(":")[2].split("/")[0]), url.split("token=")[1]
    try:
        scene = json.load(urllib.request.urlopen("http://127.0.0.1:%d/api/scene?token=%s" % (port, token)))
        first = dict(scene["first_view"], width=w, height=h)
        ws = websocket.create_connection("ws://127.0.0.1:%d/ws?token=%s" % (port, token), timeout=600)
        settings = {"repeat_level": a.L}

        def frame():
            data = ws.recv()
            n = int.from_bytes(data[:4], "little")
            return json.loads(data[4:4 + n])

        def send(seq, angle):
            t, e = first["target"], first["eye"]
            dx, dy = e[0] - t[0], e[1] - t[1]
            cam = dict(first, eye=[t[0] + math.cos(angle) * dx - math.sin(angle) * dy,
                                   t[1] + math.sin(angle) * dx + math.cos(angle) * dy, e[2]])
            ws.send(json.dumps({"type": "view", "seq": seq, "camera": cam, "settings": settings}))

        # Orbit: a new camera as soon as the frame of the last one arrives.
        latencies = []
        start = time.time()
        for k in range(a.frames + 1):
            t0 = time.time()
            send(k + 1, math.radians(3 * k))
            while frame()["seq"] != k + 1:
                pass
            if k > 0:
                latencies.append(1000 * (time.time() - t0))
        orbit = time.time() - start
        # At rest: to the converged frame.
        converge = []
        for r in range(2):
            t0 = time.time()
            send(1000 + r, math.radians(90 + r))
            while True:
                f = frame()
                if f["seq"] == 1000 + r and f["converged"]:
                    break
            converge.append(time.time() - t0)
        latencies.sort()
        print("%s np %d: first frame p50 %.1f ms p95 %.1f ms, %.1f frames/s, converged %.2f s (points %d)" % (
            a.size, a.np, statistics.median(latencies), latencies[int(math.ceil(0.95 * len(latencies))) - 1],
            (a.frames + 1) / orbit, statistics.median(converge), scene["points"]))
        ws.close()
    finally:
        server.terminate()
        server.wait()


if __name__ == "__main__":
    sys.exit(main())
