"""candi view in a real browser: Debian's chromium, headless, driven through DevTools.

Usage: view_browser_test.py CANDI SOURCE_DIR   (ctest runs it; skips, saying why, without chromium)

The scene is the bundled foundation drawing made into points by `candi foundation` and packed by
`candi pack`: the project's own code, no fixture files. Checks: the converged frame equals `candi
render` of the same view, seed and L (bit for bit, as sent and as drawn on the canvas); a mouse
drag moves the camera and brings new frames; bad requests and messages are refused and the server
keeps serving. Timeouts only catch hangs; no verdict depends on speed.
"""
import atexit
import base64
import http.client
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import devtools  # noqa: E402
import websocket  # noqa: E402

CANDI = SOURCE = None
HANG = 600  # seconds: a hang, not a speed limit


def run(*args):
    r = subprocess.run([CANDI, *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise AssertionError("candi %s failed (%d):\n%s" % (" ".join(args), r.returncode, r.stderr[-3000:]))
    return r


class Viewer:
    """`candi view` on a free port; the URL it prints."""

    def __init__(self, *inputs, launcher=(), args=(), env=None, preexec_fn=None):
        self.process = subprocess.Popen([*launcher, CANDI, "view", *inputs, "--port", "0", *args],
                                        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                                        preexec_fn=preexec_fn)
        line = self.process.stdout.readline()
        if not line.startswith("candi view: "):
            self.process.kill()
            raise AssertionError("candi view printed %r; stderr:\n%s" % (line, self.process.stderr.read()[-3000:]))
        # stderr is read as it comes (a server that logs much must never block on a full pipe).
        self.stderr_lines = []
        self.stderr_reader = threading.Thread(target=lambda: self.stderr_lines.extend(self.process.stderr),
                                              daemon=True)
        self.stderr_reader.start()
        self.url = line.split(": ", 1)[1].strip()
        self.port = int(self.url.split(":")[2].split("/")[0])
        self.token = self.url.split("token=")[1]
        atexit.register(self.stop)

    def request(self, method, path, headers=None, body=None):
        c = http.client.HTTPConnection("127.0.0.1", self.port, timeout=HANG)
        c.putrequest(method, path, skip_host=True, skip_accept_encoding=True)
        headers = dict(headers or {})
        headers.setdefault("Host", "127.0.0.1:%d" % self.port)
        for k, v in headers.items():
            c.putheader(k, v)
        if body is not None:
            c.putheader("Content-Length", str(len(body)))
        c.endheaders(body.encode() if isinstance(body, str) else body)
        r = c.getresponse()
        data = r.read()
        c.close()
        return r.status, data

    def scene(self):
        """The scene the viewer serves (GET /api/scene), parsed."""
        status, data = self.request("GET", "/api/scene?token=" + self.token)
        assert status == 200, (status, data[:300])
        return json.loads(data)

    def stop(self):
        """Ends the process if it still runs: at exit, after a failure that skipped close() (mpirun
        passes SIGTERM on to its ranks, which SIGKILL would leave running)."""
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout=60)
            except subprocess.TimeoutExpired:
                self.process.kill()

    def close(self):
        self.process.terminate()
        self.process.wait(timeout=60)
        self.stderr_reader.join(timeout=60)
        self.stderr = "".join(self.stderr_lines)


def foundation_archive(folder, count):
    """The bundled foundation drawing as `count` points (`candi foundation --split`: one file per
    layer) packed into folder/foundation.archive, an archive of four layers; its path."""
    run("foundation", os.path.join(SOURCE, "examples", "borobudur", "foundation.dxf"), "-o",
        os.path.join(folder, "foundation.ply"), "--count", str(count), "--no-self-intersection", "--split")
    layers = sorted(f for f in os.listdir(folder) if f.startswith("foundation_") and f.endswith(".ply"))
    assert len(layers) == 4, layers
    archive = os.path.join(folder, "foundation.archive")
    run("pack", *[os.path.join(folder, f) for f in layers], "-o", archive)
    return archive


def script_main(check, prefix):
    """The main of a script test (view_load_test.py, view_mpi_test.py): CANDI and SOURCE from its
    arguments, then check(work) in a temporary folder removed afterwards. check returns the list of
    failures; the exit status is 1 when there are any (printed), else 0."""
    if len(sys.argv) < 3:
        sys.exit("usage: %s CANDI SOURCE_DIR" % os.path.basename(sys.argv[0]))
    global CANDI, SOURCE
    CANDI, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    work = tempfile.mkdtemp(prefix=prefix)
    try:
        failures = check(work)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    if failures:
        print("FAILED:\n" + "\n".join(failures))
        return 1
    print("OK")
    return 0


class ViewerPage(unittest.TestCase):
    """A test class's page: `candi view` on the foundation archive of POINTS points, open in headless
    chromium at 640x480, its first frame drawn. No tests of its own."""
    POINTS = 200000

    @classmethod
    def open_viewer(cls):
        """The viewer the page opens (a subclass may serve other data from cls.dir)."""
        cls.archive = foundation_archive(cls.dir, cls.POINTS)
        return Viewer(cls.archive)

    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="candi-view-test-")
        cls.viewer = cls.open_viewer()
        cls.browser = devtools.Browser(640, 480)
        cls.browser.call("Page.enable")
        cls.browser.call("Page.navigate", url=cls.viewer.url)
        cls.browser.wait_for("window.candiViewer && candiViewer.stats.lastFrame !== null", HANG, "a first frame")

    @classmethod
    def tearDownClass(cls):
        cls.browser.close()
        cls.viewer.close()
        shutil.rmtree(cls.dir, ignore_errors=True)

    def wait_converged(self):
        # Converged, and for the page's latest camera (no view message still on its way).
        return self.browser.wait_for(
            "(() => { const f = candiViewer.stats.lastFrame; return f && f.converged && "
            "f.seq === candiViewer.stats.drawnSeq && f.seq === candiViewer.viewSeq() ? f : null; })()",
            HANG, "convergence")


class ViewInBrowser(ViewerPage):

    def test_1_converged_frame_is_candi_render(self):
        frame = self.wait_converged()
        self.assertEqual(frame["format"], "png")
        self.assertEqual(frame["ensembles"], frame["repeat_level"])
        view_json = self.browser.evaluate("candiViewer.viewJson()")
        settings = self.browser.evaluate("candiViewer.settings()")
        view = os.path.join(self.dir, "view.json")
        with open(view, "w") as f:
            f.write(view_json)
        reference = os.path.join(self.dir, "reference.png")
        run("render", self.archive, "--view", view, "-L", str(settings["repeat_level"]), "--seed",
            str(settings["seed"]), "--background", ",".join(str(c) for c in settings["background"]),
            "--brightness", "auto" if settings["brightness"] == "auto" else str(settings["brightness"]),
            "-o", reference)
        with open(reference, "rb") as f:
            w, h, ch, expected = devtools.decode_png(f.read())
        sent = base64.b64decode(self.browser.evaluate("candiViewer.pngBase64()", await_promise=True))
        sw, sh, sch, got = devtools.decode_png(sent)
        self.assertEqual((sw, sh, sch), (w, h, 3))
        self.assertEqual(got, expected, "the converged frame differs from candi render's image")
        # What the canvas shows: the same pixels (RGBA).
        canvas = self.browser.evaluate("candiViewer.canvasPixels()")
        self.assertEqual(len(canvas), w * h * 4)
        rgb = bytes(v for i, v in enumerate(canvas) if i % 4 != 3)
        self.assertEqual(rgb, expected, "the canvas differs from candi render's image")
        # Not a blank image: the foundation covers part of it.
        background = bytes(settings["background"])
        covered = sum(1 for p in range(w * h) if expected[3 * p:3 * p + 3] != background)
        self.assertGreater(covered, w * h // 50)

    def test_2_drag_moves_camera_and_brings_frames(self):
        self.wait_converged()
        before = self.browser.evaluate("candiViewer.camera()")
        frames = self.browser.evaluate("candiViewer.stats.framesReceived")
        seq = self.browser.evaluate("candiViewer.stats.drawnSeq")
        b = self.browser
        b.mouse("mouseMoved", 320, 240, buttons=0, button="none")
        b.mouse("mousePressed", 320, 240)
        for k in range(1, 11):
            b.mouse("mouseMoved", 320 + 10 * k, 240 + 3 * k)
            time.sleep(0.02)
        b.mouse("mouseReleased", 420, 270, buttons=0)
        after = b.evaluate("candiViewer.camera()")
        self.assertNotEqual(before["eye"], after["eye"], "the drag did not orbit the camera")
        self.assertEqual(before["target"], after["target"], "an orbit keeps the target")
        b.wait_for("candiViewer.stats.drawnSeq > %d && candiViewer.stats.framesReceived > %d" % (seq, frames),
                   HANG, "a frame of the new camera")
        frame = self.wait_converged()
        self.assertGreater(frame["seq"], seq)

    def converged_pixels(self):
        self.wait_converged()
        w, h, ch, rgb = devtools.decode_png(
            base64.b64decode(self.browser.evaluate("candiViewer.pngBase64()", await_promise=True)))
        return rgb

    def opacity_map(self):
        """Per pixel, the opacity of what is drawn: from the converged images over black and over
        white (gain 1), alpha = 1 - (white - black) / 255, whatever the points' colours."""
        b = self.browser
        b.evaluate("candiViewer.setSettings({background: [0, 0, 0], brightness: 'none', point_size: 6})")
        black = self.converged_pixels()
        b.evaluate("candiViewer.setSettings({background: [255, 255, 255]})")
        white = self.converged_pixels()
        b.evaluate("candiViewer.setSettings({point_size: 1})")
        return [1 - sum(white[3 * p + c] - black[3 * p + c] for c in range(3)) / (3 * 255.0)
                for p in range(len(black) // 3)]

    def test_3_layer_opacity_slider_follows_the_point_number_law(self):
        b = self.browser
        scene_layers = b.evaluate("candiViewer.settings().layers.length")
        self.assertEqual(scene_layers, 4)
        # Only the first layer shown: untick the others as a user would.
        for i in (1, 2, 3):
            b.evaluate("(() => { const e = document.getElementById('layer-visible-%d'); e.checked = false; "
                       "e.dispatchEvent(new Event('input')); })()" % i)
        self.assertEqual(b.evaluate("candiViewer.settings().layers"), [1, 0, 0, 0])
        full = self.opacity_map()
        # The slider to half the points.
        b.evaluate("(() => { const e = document.getElementById('layer-share-0'); e.value = '0.5'; "
                   "e.dispatchEvent(new Event('input')); })()")
        self.assertEqual(b.evaluate("candiViewer.settings().layers"), [0.5, 0, 0, 0])
        half = self.opacity_map()
        covered = [p for p, a in enumerate(full) if a > 0.02]
        self.assertGreater(len(covered), 2000, "the layer covers too little of the image to measure")
        measured = sum(half[p] for p in covered) / len(covered)
        law = sum(1 - (1 - min(full[p], 1.0)) ** 0.5 for p in covered) / len(covered)
        before = sum(full[p] for p in covered) / len(covered)
        print("layer opacity: %.4f at f = 1, %.4f at f = 0.5, the law predicts %.4f (%d pixels)"
              % (before, measured, law, len(covered)))
        self.assertGreater(before, 0.3, "too transparent to tell the law from a straight line")
        self.assertLess(measured, 0.9 * before, "halving the points did not lower the opacity")
        # The law, not halving: 1 - (1 - a)^0.5 is well above a / 2 at these opacities.
        self.assertGreater(law - before / 2, 0.03)
        self.assertAlmostEqual(measured, law, delta=0.02)
        # Every layer back, at its full share.
        b.evaluate("document.getElementById('layers-all').click()")
        b.evaluate("candiViewer.setSettings({background: [0, 0, 0], brightness: 'auto'})")
        self.assertEqual(b.evaluate("candiViewer.settings().layers"), [1, 1, 1, 1])

    def test_4_bad_requests_are_refused_and_the_server_keeps_serving(self):
        v = self.viewer
        t = v.token
        good = "/api/scene?token=" + t
        cases = [
            ("GET", "/../../etc/passwd?token=" + t, {}, None, 404),
            ("GET", "/%2e%2e/%2e%2e/etc/passwd?token=" + t, {}, None, 404),
            ("GET", "/viewer.js/../../archive?token=" + t, {}, None, 404),
            ("GET", "/api/scene?token=wrong", {}, None, 403),
            ("GET", "/api/scene", {}, None, 403),
            ("GET", good, {"Host": "attacker.example:%d" % v.port}, None, 403),
            ("GET", good, {"Host": "127.0.0.1:1"}, None, 403),
            ("GET", good, {"Origin": "http://attacker.example"}, None, 403),
            ("POST", good, {}, "{}", 405),
            ("GET", good, {"X-Big": "a" * 20000}, None, 431),
            ("GET", "/" + "a" * 3000 + "?token=" + t, {}, None, 414),
            ("GET", good, {}, "x" * 5000, 413),
        ]
        for method, path, headers, body, status in cases:
            got, _ = v.request(method, path, headers, body)
            self.assertEqual(got, status, "%s %s %s" % (method, path[:60], list(headers)))
            self.assertEqual(v.request("GET", good)[0], 200, "the server stopped answering after " + path[:60])
        # A request that is not HTTP at all.
        import socket
        s = socket.create_connection(("127.0.0.1", v.port), timeout=HANG)
        s.sendall(b"\x16\x03\x01\x02\x00garbage\r\n\r\n")
        reply = s.recv(100)
        s.close()
        self.assertTrue(reply.startswith(b"HTTP/1.1 400") or reply == b"", reply)
        self.assertEqual(v.request("GET", good)[0], 200)

        ws_url = "ws://127.0.0.1:%d/ws?token=%s" % (v.port, t)
        # Wrong token: no upgrade.
        with self.assertRaises(websocket.WebSocketBadStatusException):
            websocket.create_connection("ws://127.0.0.1:%d/ws?token=x" % v.port, timeout=HANG)
        # Cross-site page: refused by its Origin.
        with self.assertRaises(websocket.WebSocketBadStatusException):
            websocket.create_connection(ws_url, timeout=HANG, origin="http://attacker.example")
        camera = json.loads(self.browser.evaluate("candiViewer.viewJson()"))
        bad_messages = [
            "{not json",
            json.dumps({"type": "view", "seq": 1}),
            json.dumps({"type": "view", "seq": 1, "camera": dict(camera, eye=[0, 0, "x"])}),
            json.dumps({"type": "view", "seq": 1, "camera": dict(camera, width=100000)}),
            json.dumps({"type": "view", "seq": 1, "camera": camera, "settings": {"repeat_level": 0}}),
            json.dumps({"type": "view", "seq": 1, "camera": camera, "settings": {"point_size": float("nan")}})
            .replace("NaN", "1e999"),
            json.dumps({"type": "hack"}),
            "[" * 100000,
        ]
        for m in bad_messages:
            ws = websocket.create_connection(ws_url, timeout=HANG)
            ws.send(m)
            # The error (not for a message beyond the size limit, refused by the framing), then the close.
            replies = []
            with self.assertRaises((websocket.WebSocketConnectionClosedException, ConnectionError)):
                while True:
                    r = ws.recv()
                    if r in ("", b""):
                        raise websocket.WebSocketConnectionClosedException()
                    replies.append(r)
            if len(m) < 16384:
                self.assertEqual(len(replies), 1, m[:80])
                self.assertIn('"error"', replies[0], m[:80])
            self.assertFalse(any(isinstance(r, bytes) for r in replies), "a frame for a bad message")
            ws.close()
        # The next good page is served.
        ws = websocket.create_connection(ws_url, timeout=HANG)
        small = dict(camera, width=64, height=48)
        ws.send(json.dumps({"type": "view", "seq": 5, "camera": small, "settings": {"repeat_level": 4}}))
        data = ws.recv()
        self.assertIsInstance(data, bytes)
        n = int.from_bytes(data[:4], "little")
        header = json.loads(data[4:4 + n])
        self.assertEqual((header["seq"], header["width"], header["height"]), (5, 64, 48))
        ws.close()

    def test_5_token_leaves_the_address_bar_and_a_reload_works_by_the_cookie(self):
        self.wait_converged()
        self.assertNotIn("token", self.browser.evaluate("location.href"))
        self.assertEqual(self.browser.evaluate("location.search"), "")
        # The history entry was replaced, not added: no entry holds the token.
        entries = self.browser.call("Page.getNavigationHistory")["entries"]
        self.assertTrue(any(e["url"].split("#")[0].endswith(":%d/" % self.viewer.port) for e in entries), entries)
        self.assertFalse([e["url"] for e in entries if "token" in e["url"]])
        # A reload (no token in the address) is authorised by the cookie and draws again.
        self.browser.call("Page.reload")
        self.browser.wait_for("window.candiViewer && candiViewer.stats.lastFrame !== null", HANG,
                              "a frame after the reload")
        self.assertNotIn("token", self.browser.evaluate("location.href"))


class ViewPreviewInBrowser(ViewerPage):
    """`candi view FILE...` of more points than twice --preview: a preview (one point in k) is
    served first, then the whole archive replaces it. Whenever the swap comes (before or after the
    page opened), the page ends showing every point: the converged frame is candi render's of the
    files packed whole by candi pack."""
    POINTS = 60000

    @classmethod
    def open_viewer(cls):
        run("foundation", os.path.join(SOURCE, "examples", "borobudur", "foundation.dxf"), "-o",
            os.path.join(cls.dir, "foundation.ply"), "--count", str(cls.POINTS), "--no-self-intersection", "--split")
        cls.files = [os.path.join(cls.dir, f) for f in sorted(os.listdir(cls.dir))
                     if f.startswith("foundation_") and f.endswith(".ply")]
        assert len(cls.files) == 4, cls.files
        return Viewer(*cls.files, args=("--preview", "5000"))

    def test_1_the_whole_archive_replaces_the_preview(self):
        # The whole archive is served: the scene says so, and so does the page's title.
        self.browser.wait_for("!document.getElementById('title').textContent.includes('preview')", HANG,
                              "the title of the whole archive")
        scene = self.viewer.scene()
        self.assertNotIn("preview", scene)
        self.assertEqual(scene["points"], self.POINTS)
        self.assertIn(" %s points" % format(self.POINTS, ","), self.browser.evaluate(
            "document.getElementById('title').textContent"))
        # The page asks for an image again (a camera change after the swap) and it converges to
        # candi render's image of the whole archive.
        self.browser.evaluate("candiViewer.setSettings({repeat_level: 16})")
        frame = self.wait_converged()
        view = os.path.join(self.dir, "view.json")
        with open(view, "w") as f:
            f.write(self.browser.evaluate("candiViewer.viewJson()"))
        settings = self.browser.evaluate("candiViewer.settings()")
        archive = os.path.join(self.dir, "whole.archive")
        run("pack", *self.files, "-o", archive)
        reference = os.path.join(self.dir, "whole.png")
        run("render", archive, "--view", view, "-L", str(settings["repeat_level"]), "--seed", str(settings["seed"]),
            "--background", ",".join(str(c) for c in settings["background"]),
            "--brightness", "auto" if settings["brightness"] == "auto" else str(settings["brightness"]), "-o", reference)
        with open(reference, "rb") as f:
            expected = devtools.decode_png(f.read())
        sent = base64.b64decode(self.browser.evaluate("candiViewer.pngBase64()", await_promise=True))
        self.assertEqual(devtools.decode_png(sent), expected, "the converged frame is not the whole archive's")
        self.assertEqual(frame["ensembles"], settings["repeat_level"])
        # The viewer said it served a preview first, and then every point.
        deadline = time.time() + HANG
        while not any("points packed: the pages show them" in line for line in self.viewer.stderr_lines):
            self.assertLess(time.time(), deadline, "no line saying every point is shown")
            time.sleep(0.1)
        log = "".join(self.viewer.stderr_lines)
        self.assertIn("a preview, one point in ", log)
        self.assertIn("of %d, until all are packed" % self.POINTS, log)


class ViewPreviewInterrupted(unittest.TestCase):
    """SIGTERM while the whole archive is packed behind a preview (or after, whichever comes
    first): the viewer ends by the signal and leaves no temporary archive behind, neither the
    preview's nor the half-packed whole one."""

    def test_no_temporary_archive_is_left(self):
        work = tempfile.mkdtemp(prefix="candi-view-interrupt-")
        try:
            run("foundation", os.path.join(SOURCE, "examples", "borobudur", "foundation.dxf"), "-o",
                os.path.join(work, "hill.ply"), "--count", "1500000", "--no-self-intersection")
            tmp = os.path.join(work, "tmp")
            os.mkdir(tmp)
            viewer = Viewer(os.path.join(work, "hill.ply"), args=("--preview", "10000"), env=dict(os.environ, TMPDIR=tmp))
            self.assertTrue(os.listdir(tmp), "the preview's archive is in TMPDIR while the viewer runs")
            viewer.close()  # SIGTERM
            self.assertEqual(viewer.process.returncode, -15, viewer.stderr[-2000:])
            self.assertEqual(os.listdir(tmp), [], "temporary archives left behind")
        finally:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: view_browser_test.py CANDI SOURCE_DIR")
    CANDI, SOURCE = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    if devtools.find_chromium() is None:
        print("SKIP: chromium is not installed (scripts/deps.sh installs it)")
        sys.exit(0)
    unittest.main(argv=[sys.argv[0], "-v"])
