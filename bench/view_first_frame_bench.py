"""`candi view FILE` from the start of the process to its first frame, as a page on 127.0.0.1 sees
it (over the viewer's WebSocket, the first view of the scene at L = 100), and to the converged
frame of every point; with a preview (the default) and without (--preview 0), alternated, median
of --runs runs each. Issue 38's target: the first frame within 3 s at 10^8 points.

Usage: /usr/bin/python3 bench/view_first_frame_bench.py CANDI FILE [--runs 3] [--preview 10000000]
       (FILE: e.g. bench/first_image_bench's terrain-100000000.ply)
"""
import argparse
import json
import statistics
import subprocess
import time
import urllib.request

import websocket  # python3-websocket


def one_run(candi, path, preview):
    start = time.monotonic()
    p = subprocess.Popen([candi, "view", path, "--port", "0", "--preview", str(preview)], stdout=subprocess.PIPE,
                         stderr=subprocess.DEVNULL, text=True)
    try:
        url = p.stdout.readline().split(": ", 1)[1].strip()
        served = time.monotonic() - start
        port, token = int(url.split(":")[2].split("/")[0]), url.split("token=")[1]
        scene = json.loads(urllib.request.urlopen("http://127.0.0.1:%d/api/scene?token=%s" % (port, token)).read())
        ws = websocket.create_connection("ws://127.0.0.1:%d/ws?token=%s" % (port, token),
                                         header=["Origin: http://127.0.0.1:%d" % port])
        ws.send(json.dumps({"type": "view", "seq": 1, "camera": scene["first_view"],
                            "settings": {"repeat_level": 100}}))
        whole = "preview" not in scene
        first = converged = None
        while converged is None:
            m = ws.recv()
            if isinstance(m, str):
                whole = whole or json.loads(m).get("type") == "scene"
                continue
            n = int.from_bytes(m[:4], "little")
            header = json.loads(m[4:4 + n])
            if first is None:
                first = time.monotonic() - start
            if header["converged"] and whole:
                converged = time.monotonic() - start
        ws.close()
        return served, first, converged
    finally:
        p.terminate()
        p.wait()


def main():
    a = argparse.ArgumentParser()
    a.add_argument("candi")
    a.add_argument("file")
    a.add_argument("--runs", type=int, default=3)
    a.add_argument("--preview", type=int, default=10000000)
    o = a.parse_args()
    results = {o.preview: [], 0: []}
    for _ in range(o.runs):
        for preview in (o.preview, 0):
            results[preview].append(one_run(o.candi, o.file, preview))
    print("candi view %s: seconds from the start, median of %d runs" % (o.file, o.runs))
    print("%-16s %12s %14s %26s" % ("preview", "page served", "first frame", "every point converged"))
    for preview, runs in results.items():
        med = [statistics.median(r[k] for r in runs) for k in range(3)]
        print("%-16s %12.2f %14.2f %26.2f" % (preview if preview else "none", *med))


if __name__ == "__main__":
    main()
