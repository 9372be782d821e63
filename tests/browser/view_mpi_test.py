"""candi view under mpirun: rank 0 serves, every rank draws its share of each image's ensembles.

Usage: view_mpi_test.py CANDI SOURCE_DIR   (skips, saying why, without mpirun)

A page (a WebSocket client here) asks for a view; the converged frame of `mpirun -np 2 candi view`
must equal `candi render` of the same view in one process, bit for bit, and so must a frame with a
layer hidden equal the one-process viewer's.
"""
import json
import os
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import devtools  # noqa: E402
from view_browser_test import Viewer, foundation_archive, run, script_main  # noqa: E402
import websocket  # noqa: E402


def converged(viewer, view, settings):
    ws = websocket.create_connection("ws://127.0.0.1:%d/ws?token=%s" % (viewer.port, viewer.token), timeout=600)
    ws.send(json.dumps({"type": "view", "seq": 1, "camera": view, "settings": settings}))
    while True:
        data = ws.recv()
        if isinstance(data, str):
            raise AssertionError("the server said: " + data)
        n = int.from_bytes(data[:4], "little")
        header = json.loads(data[4:4 + n])
        if header["converged"]:
            ws.close()
            return devtools.decode_png(data[4 + n:])


def check(work):
    archive = foundation_archive(work, 100000)
    launcher = ["mpirun", "--oversubscribe", "-np", "2"] + (["--allow-run-as-root"] if os.geteuid() == 0 else [])
    mpi = Viewer(archive, launcher=launcher)
    one = Viewer(archive)
    view = dict(one.scene()["first_view"], width=200, height=150)
    settings = {"repeat_level": 20, "seed": 3, "background": [0, 0, 0], "brightness": "auto"}
    got = converged(mpi, view, settings)
    view_file = os.path.join(work, "view.json")
    with open(view_file, "w") as f:
        json.dump(view, f)
    reference = os.path.join(work, "ref.png")
    run("render", archive, "--view", view_file, "-L", "20", "--seed", "3", "--background", "0,0,0", "-o", reference)
    with open(reference, "rb") as f:
        expected = devtools.decode_png(f.read())
    failures = []
    if got != expected:
        failures.append("mpirun -np 2 candi view's converged frame differs from candi render's image")
    hidden = dict(settings, layers=[1, 0, 1, 0.5])
    a, b = converged(mpi, view, hidden), converged(one, view, hidden)
    if a != b:
        failures.append("with layer shares, the MPI viewer's frame differs from the one-process viewer's")
    if a == got:
        failures.append("hiding layers did not change the image")
    mpi.close()
    one.close()
    return failures + ([mpi.stderr[-3000:]] if failures else [])


if __name__ == "__main__":
    if shutil.which("mpirun") is None:
        print("SKIP: mpirun is not installed (Debian: openmpi-bin)")
        sys.exit(0)
    sys.exit(script_main(check, "candi-view-mpi-"))
