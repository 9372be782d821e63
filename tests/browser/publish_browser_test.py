#!/usr/bin/python3
"""candi publish in a real browser: Debian's chromium, headless, with its software WebGL2
(SwiftShader), the site served by `python3 -m http.server` (no HTTP Range support).

- WebGL2 must be there: a page without it is a failure, not a skip.
- The converged image equals candi render's of the same archive, view, seed and L, perspective,
  orthographic and opaque (the figures
  are printed; the bound is >= 99 % of pixels within 1 level and at most 0.01 % beyond 8).
- Layer shares and a clip box set on the page: candi render --view of the page's saved view
  (which carries both) gives the same image, so the shares follow candi's point-number law;
  picks on the client take only drawn points (not the hidden layer, not the clipped part).
- At 2 Mbit/s (DevTools' network emulation) the first image is drawn after the first ensemble's
  bytes (page 0 of every group), not after the whole data; DevTools sees every page 0 requested
  before any later page.
- A budget smaller than the data: the page holds at most it, before and after moving.
- A damaged, a missing and a truncated data file: the page names each and draws the rest, and
  never says "converged" (tests/browser/publish_hostile_test.py has the hostile cases).
- A build in survey coordinates (10^6 m): the same image as candi render's; its licence,
  annotations and provenance (measured or reconstructed) reach the page.
- Points packed coloured by a field: the legend on the page, and a pick's value on the client
  (decoded from the point's colour) equal to the picked point's field.
- candi publish on bad input exits 2 naming the path and leaves nothing behind.
Usage: publish_browser_test.py CANDI SOURCE_DIR"""
import base64
import json
import os
import shutil
import socket
import stat
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import view_browser_test as vb  # noqa: E402
from devtools import Browser, decode_png, find_chromium  # noqa: E402

L = 16


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Served:
    """`python3 -m http.server` on 127.0.0.1 over `folder`."""

    def __init__(self, folder):
        self.port = free_port()
        self.process = subprocess.Popen([sys.executable, "-m", "http.server", "-b", "127.0.0.1", "-d", folder,
                                         str(self.port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        end = time.time() + 30
        while time.time() < end:
            try:
                socket.create_connection(("127.0.0.1", self.port), timeout=1).close()
                return
            except OSError:
                time.sleep(0.1)
        raise AssertionError("http.server did not listen")

    def url(self, query=""):
        return "http://127.0.0.1:%d/%s" % (self.port, query)

    def close(self):
        self.process.terminate()
        self.process.wait(timeout=30)


def converged(browser, what):
    time.sleep(0.3)
    browser.wait_for("window.candiViewer && window.candiViewer.progress && !window.candiViewer.dirty() && "
                     "window.candiViewer.progress().converged", 300, what)


def compare(browser, work, archive, name, failures):
    """The page's converged image against candi render --view of the page's saved view."""
    view = os.path.join(work, name + ".view.json")
    with open(view, "w") as f:
        f.write(browser.evaluate("window.candiViewer.viewJson()"))
    settings = browser.evaluate("window.candiViewer.settings()")
    web = base64.b64decode(browser.evaluate("window.candiViewer.imageRgb()"))
    png = os.path.join(work, name + ".png")
    brightness = "none" if settings["brightness"] == "none" else "auto"
    vb.run("render", archive, "--view", view, "-L", str(settings["repeat_level"]), "--seed", str(settings["seed"]),
           "--brightness", brightness, "-o", png, *(["--opaque"] if settings["opaque"] else []))
    with open(png, "rb") as f:
        w, h, channels, ref = decode_png(f.read())
    if channels != 3 or len(web) != len(ref):
        failures.append("%s: the page's image is %d bytes, candi render's %dx%dx%d" % (name, len(web), w, h, channels))
        return None
    worst = [max(abs(ref[3 * i + k] - web[3 * i + k]) for k in range(3)) for i in range(w * h)]
    within1 = sum(1 for d in worst if d <= 1) / len(worst)
    beyond8 = sum(1 for d in worst if d > 8)
    covered = sum(1 for i in range(w * h) if any(ref[3 * i:3 * i + 3]))
    print("%s: %dx%d, %d pixels drawn; %.4f %% within 1 level, %d beyond 8, %d identical, largest difference %d"
          % (name, w, h, covered, 100 * within1, beyond8, sum(1 for d in worst if d == 0), max(worst)))
    if covered < 0.02 * w * h:
        failures.append("%s: candi render drew only %d pixels: the view shows nothing to compare" % (name, covered))
    # The GPU projects in float from the chunk's quantized steps (candi from the dequantized
    # double), so a point near a depth tie may win on one and lose on the other: a few pixels.
    if within1 < 0.99 or beyond8 > 1e-4 * w * h:
        failures.append("%s: %.4f %% of pixels within 1 level (>= 99 %% wanted), %d beyond 8 (<= 0.01 %% wanted)"
                        % (name, 100 * within1, beyond8))
    return web


def coloured_site(work):
    failures = []
    # A 20 x 10 m sheet at survey coordinates whose distance is (x - 10) / 10: -1 west, +1 east;
    # one point has none (nan), one lies outside the range.
    E, N, H = 416000.0, 9168000.0, 100.0
    ply = os.path.join(work, "deviation.ply")
    with open(ply, "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 20000\nproperty double x\nproperty double y\n"
                "property double z\nproperty float scalar_distance\nend_header\n")
        for i in range(200):
            for j in range(100):
                x, y = i * 0.1 + 0.05, j * 0.1 + 0.05
                d = "nan" if (i, j) == (0, 0) else "5" if (i, j) == (0, 1) else repr((x - 10) / 10)
                f.write("%.3f %.3f %.3f %s\n" % (E + x, N + y, H, d))
    archive = os.path.join(work, "deviation.archive")
    vb.run("pack", ply, "-o", archive, "--colour-by", "distance", "--field-range", "-1,1")
    vb.run("publish", archive, "-o", os.path.join(work, "deviation_site"), "-L", "4")
    served = Served(os.path.join(work, "deviation_site"))
    browser = Browser(640, 480, webgl=True)
    try:
        browser.call("Page.navigate", url=served.url())
        converged(browser, "the coloured site")
        legend = browser.evaluate("(() => { const l = document.getElementById('legend'); return {hidden: l.hidden, "
                                  "text: l.innerText}; })()")
        print("coloured site legend: %r" % legend["text"])
        if legend["hidden"]:
            failures.append("the coloured site shows no legend")
        for words in ("distance", "-1", "1 outside", "1 without a value"):
            if words not in legend["text"]:
                failures.append("the coloured site's legend does not say %r: %r" % (words, legend["text"]))
        # Straight down at x = 15 m (distance 0.5).
        cx, cy = E + 15, N + 5
        browser.evaluate("window.candiViewer.setCamera(%s)" % json.dumps(
            {"eye": [cx, cy, H + 30], "target": [cx, cy, H], "up": [0, 1, 0], "projection": "perspective",
             "fov_y_deg": 40, "near": 0.01}))
        converged(browser, "the coloured site from above")
        # The site picks a point under the very pixel: the pixel of a point of the sheet.
        q = browser.evaluate("window.candiViewer.project(%s)" % json.dumps([E + 15.05, N + 5.05, H]))
        r = browser.evaluate("window.candiViewer.pick(%r, %r)" % (int(q[0]) + 0.5, int(q[1]) + 0.5),
                             await_promise=True)
        hit = r["hits"][0] if r.get("hit") else None
        print("coloured site pick: %s" % hit)
        if hit is None or hit.get("value") is None:
            failures.append("a pick on the coloured site gave no value: %s" % r)
        else:
            expected = (hit["point"][0] - E - 10) / 10
            if not (abs(hit["value"] - expected) <= hit["value_half_width"] + 1e-3 and abs(hit["value"] - 0.5) < 0.05
                    and hit["value_half_width"] < 0.01):
                failures.append("the coloured site's pick: value %s +- %s, the point's %s"
                                % (hit["value"], hit["value_half_width"], expected))
    finally:
        browser.close()
        served.close()
    return failures


def check(work):
    failures = []
    archive = vb.foundation_archive(work, 120000)
    site = os.path.join(work, "site")
    out = vb.run("publish", archive, "-o", site, "-L", str(L), "--group-points", "40000")
    print(out.stdout.strip())
    with open(os.path.join(site, "site.json")) as f:
        index = json.load(f)
    groups = index["data"]["groups"]
    page0 = sum(g["pages"][0][0] for g in groups)
    total = sum(p[0] for g in groups for p in g["pages"])
    if len(groups) < 3:
        failures.append("the site has %d groups; the test wants several" % len(groups))

    served = Served(site)
    browser = Browser(640, 480, webgl=True)
    try:
        # 2 Mbit/s: the data takes seconds to arrive, the first ensemble's a fraction of that.
        browser.call("Network.enable")
        browser.call("Network.emulateNetworkConditions", offline=False, latency=0, downloadThroughput=250000,
                     uploadThroughput=250000)
        browser.call("Page.navigate", url=served.url())
        browser.wait_for("window.candiViewer && 'webgl2' in window.candiViewer", 120, "the page")
        if not browser.evaluate("window.candiViewer.webgl2"):
            return ["chromium gave no WebGL2 (flags %s): the site cannot be tested" % " ".join(Browser.WEBGL_ARGS)]
        converged(browser, "the first converged image")
        progress = browser.evaluate("window.candiViewer.progress()")
        print("first image after %d bytes of data (page 0 of every group: %d; all: %d); converged after %d"
              % (progress["firstImageBytes"], page0, total, progress["bytesReceived"]))
        if not page0 <= progress["firstImageBytes"] < total / 2:
            failures.append("the first image came after %d bytes; page 0 of every group is %d, all %d"
                            % (progress["firstImageBytes"], page0, total))
        # The requests, as DevTools saw them: every group's page 0 before any later page.
        pages = [e["params"]["request"]["url"].rsplit("/", 1)[-1] for e in browser.events
                 if e.get("method") == "Network.requestWillBeSent" and e["params"]["request"]["url"].endswith(".bin")]
        first_later = next((i for i, p in enumerate(pages) if p != "0.bin"), len(pages))
        if len(pages) != len(groups) * L or pages[:first_later].count("0.bin") != len(groups):
            failures.append("requests not in ensemble order: %s" % pages[:len(groups) + 4])
        browser.call("Network.emulateNetworkConditions", offline=False, latency=0, downloadThroughput=-1,
                     uploadThroughput=-1)
        browser.call("Network.disable")
        browser.events.clear()
        if browser.evaluate("window.candiViewer.errors().length"):
            failures.append("errors on an intact site: %s" % browser.evaluate("window.candiViewer.errors()"))

        # 1. Converged, brightness none, then automatic.
        browser.evaluate("window.candiViewer.setSettings({brightness: 'none'})")
        converged(browser, "brightness none")
        plain = compare(browser, work, archive, "plain", failures)
        browser.evaluate("window.candiViewer.setSettings({brightness: 'auto'})")
        converged(browser, "brightness auto")
        compare(browser, work, archive, "auto", failures)
        # Orthographic, and opaque (L = 1).
        camera = browser.evaluate("window.candiViewer.camera()")
        browser.evaluate("window.candiViewer.setCamera({projection: 'orthographic', ortho_height: %r})"
                         % (0.8 * max(b - a for a, b in zip(index["scene"]["bounds"]["min"],
                                                             index["scene"]["bounds"]["max"]))))
        browser.evaluate("window.candiViewer.setSettings({brightness: 'none'})")
        converged(browser, "orthographic")
        compare(browser, work, archive, "orthographic", failures)
        browser.evaluate("window.candiViewer.setCamera(%s)" % json.dumps(camera))
        browser.evaluate("window.candiViewer.setSettings({opaque: true})")
        converged(browser, "opaque")
        compare(browser, work, archive, "opaque", failures)
        browser.evaluate("window.candiViewer.setSettings({opaque: false})")

        # 2. Layer shares (one hidden, one doubled) and a clip box: candi render of the saved view.
        b = index["scene"]["bounds"]
        mid = [(b["min"][k] + b["max"][k]) / 2 for k in range(3)]
        clip = [[b["min"][0], b["min"][1], b["min"][2], 1, 0, 0], [mid[0] + 5, mid[1], mid[2], -1, 0, 0]]
        browser.evaluate("window.candiViewer.setSettings({brightness: 'none', layers: [0.5, 1, 0, 2], clip: %s})"
                         % json.dumps(clip))
        converged(browser, "shares and clipping")
        shared = compare(browser, work, archive, "shares", failures)
        # Picks on the client take only what is drawn: a point under the pixel, never of the
        # hidden layer, never clipped away.
        w, h = browser.evaluate("[window.candiViewer.camera().width, window.candiViewer.camera().height]")
        hits = 0
        for fx, fy in ((0.5, 0.5), (0.4, 0.55), (0.6, 0.45), (0.45, 0.6), (0.55, 0.5)):
            x, y = int(fx * w) + 0.5, int(fy * h) + 0.5
            m = browser.evaluate("window.candiViewer.pick(%r, %r)" % (x, y), await_promise=True)
            if not m["hit"]:
                continue
            hits += 1
            q = browser.evaluate("window.candiViewer.project(%s)" % json.dumps(m["point"]))
            if any(hit["layer"] == 2 for hit in m["hits"]) or int(q[0]) != int(x) or int(q[1]) != int(y) or \
                    m["point"][0] > mid[0] + 5 + 1e-6:
                failures.append("pick at %r, %r: %s (projects to %s)" % (x, y, m, q))
        if hits == 0:
            failures.append("no pick hit a drawn point")
        if plain is not None and shared is not None and plain == shared:
            failures.append("layer shares and clipping left the image unchanged")
        address = browser.evaluate("window.candiViewer.address()")
        if "#view=" not in address:
            failures.append("the shared address has no view: %s" % address)
        # The shared address reopens the same image.
        browser.call("Page.navigate", url="about:blank")
        time.sleep(1)
        browser.call("Page.navigate", url=address)
        time.sleep(1)
        browser.wait_for("window.candiViewer && typeof window.candiViewer.progress === 'function'", 120, "the shared address")
        converged(browser, "the shared address")
        again = base64.b64decode(browser.evaluate("window.candiViewer.imageRgb()"))
        if shared is not None and again != shared:
            failures.append("the shared address did not reopen the same image")

        # 3. A budget smaller than the data: the page holds at most it, draws what it holds, and
        # keeps within it as the camera moves (dropping the finest pages of far groups first). The
        # smallest budget the page takes is 16 MB (1 M points): a site of 1.6 M points.
        big = os.path.join(work, "big")
        os.makedirs(big)
        big_archive = vb.foundation_archive(big, 1600000)
        vb.run("publish", big_archive, "-o", os.path.join(site, "big"), "-L", str(L), "--group-points", "200000")
        with open(os.path.join(site, "big", "site.json")) as f:
            big_index = json.load(f)
        browser.call("Page.navigate", url=served.url("big/?memory_mb=16"))
        time.sleep(1)
        browser.wait_for("window.candiViewer && typeof window.candiViewer.progress === 'function'", 120, "budget page")
        converged(browser, "the image within a budget")
        held = browser.evaluate("window.candiViewer.progress()")
        status = browser.evaluate("window.candiViewer.status()")
        print("budget of %d points: %d held of %d; %s" % (held["budgetPoints"], held["heldPoints"],
                                                         big_index["scene"]["points"], status))
        if not 0 < held["heldPoints"] <= held["budgetPoints"] < big_index["scene"]["points"]:
            failures.append("budget: %s" % held)
        if "within the memory budget" not in status:
            failures.append("the status does not say the image is the budget's: %r" % status)
        camera = browser.evaluate("window.candiViewer.camera()")
        corner = big_index["scene"]["bounds"]["min"]
        browser.evaluate("window.candiViewer.setCamera({target: %s, eye: %s})"
                         % (json.dumps(corner), json.dumps([corner[k] + 0.3 * (camera["eye"][k] - camera["target"][k])
                                                           for k in range(3)])))
        converged(browser, "the image within a budget, moved")
        moved = browser.evaluate("window.candiViewer.progress()")
        if not 0 < moved["heldPoints"] <= moved["budgetPoints"] or browser.evaluate("window.candiViewer.errors().length"):
            failures.append("budget after moving: %s, errors %s" % (moved, browser.evaluate("window.candiViewer.errors()")))
        shutil.rmtree(os.path.join(site, "big"))

        # 4. Damaged, missing and truncated files.
        broken = os.path.join(work, "broken")
        shutil.copytree(site, broken)
        damaged, missing, truncated = "data/0/1.bin", "data/1/2.bin", "data/2/3.bin"
        with open(os.path.join(broken, damaged), "r+b") as f:
            data = bytearray(f.read())
            for i in range(len(data) // 2, min(len(data), len(data) // 2 + 16)):
                data[i] ^= 0x5A
            f.seek(0)
            f.write(data)
        os.remove(os.path.join(broken, missing))
        path = os.path.join(broken, truncated)
        os.truncate(path, os.path.getsize(path) // 2)
        served2 = Served(broken)
        try:
            browser.call("Page.navigate", url=served2.url())
            browser.wait_for("window.candiViewer && window.candiViewer.progress && "
                             "window.candiViewer.progress().pagesFailed >= 3", 300, "three failed pages")
            # Settled, never "converged": pages are missing.
            time.sleep(0.3)
            browser.wait_for("window.candiViewer.progress().settled && !window.candiViewer.dirty()", 300,
                             "the damaged site's image")
            status = browser.evaluate("window.candiViewer.status()")
            if "converged" in status or browser.evaluate("window.candiViewer.progress().converged"):
                failures.append("the damaged site says converged: %r" % status)
            errors = browser.evaluate("window.candiViewer.errors()")
            shown = browser.evaluate("document.getElementById('errors').textContent")
            print("damaged site: " + " | ".join(errors))
            for name in (damaged, missing, truncated):
                if not any(name in e for e in errors) or name not in shown:
                    failures.append("the page does not name %s: %s" % (name, errors))
            image = base64.b64decode(browser.evaluate("window.candiViewer.imageRgb()"))
            if not any(image):
                failures.append("the damaged site drew nothing")
        finally:
            served2.close()
    finally:
        browser.close()
        served.close()

    # 5. A build in survey coordinates (E 416000, N 9168000): its image still candi render's, and
    # its provenance, licence and annotations reach the page.
    E, N, H = 416000.0, 9168000.0, 265.0
    scene = os.path.join(work, "scene.json")
    with open(scene, "w") as f:
        json.dump({"candi_scene": 1, "name": "hill", "licence": "CC BY 4.0 (test)",
                   "render": {"repeat_level": 8, "width": 160, "height": 120},
                   "views": [{"name": "top", "camera": {"eye": [E, N - 1, H + 120], "target": [E, N, H],
                                                        "up": [0, 1, 0]}}],
                   "annotations": [{"title": "Summit", "text": "the top terrace", "position": [E, N, H + 30],
                                    "view": "top"},
                                   {"title": "Foot", "position": [E + 60, N, H]}],
                   "layers": [{"name": "hill", "kind": "foundation", "density": 0.5,
                               "world_from_layer": {"translation": [E, N, H]},
                               "dxf": os.path.join(vb.SOURCE, "examples", "borobudur", "foundation.dxf")}]}, f)
    vb.run("build", scene, "-o", os.path.join(work, "build"))
    vb.run("publish", os.path.join(work, "build"), "-o", os.path.join(work, "build_site"))
    served3 = Served(os.path.join(work, "build_site"))
    browser = Browser(640, 480, webgl=True)
    try:
        browser.call("Page.navigate", url=served3.url())
        converged(browser, "the build's site")
        browser.evaluate("window.candiViewer.setSettings({brightness: 'none', repeat_level: 8})")
        converged(browser, "the build's site, brightness none")
        compare(browser, work, os.path.join(work, "build"), "survey", failures)
        notes = browser.evaluate("window.candiViewer.annotations().map((a) => a.title)")
        about = browser.evaluate("document.getElementById('provenance').textContent")
        print("build site: annotations %s; about: %s" % (notes, about[:160]))
        if notes != ["Summit", "Foot"]:
            failures.append("annotations on the page: %s" % notes)
        for words in ("CC BY 4.0 (test)", "reconstructed", "foundation.dxf"):
            if words not in about:
                failures.append("the page's provenance does not say %r: %s" % (words, about))
        browser.evaluate("window.candiViewer.flyToAnnotation(0)")
        time.sleep(0.5)
        eye = browser.evaluate("window.candiViewer.camera().eye")
        if max(abs(a - b) for a, b in zip(eye, [E, N - 1, H + 120])) > 1e-6:
            failures.append("the annotation did not open its view: eye %s" % eye)
    finally:
        browser.close()
        served3.close()

    # 6. Points packed coloured by a field (candi pack --colour-by): the site's legend states the
    # field, range and grey counts, and a pick on the client gives the picked point's value.
    failures += coloured_site(work)

    # 7. Bad input: exit 2, the path named, nothing left behind.
    def publish(*args):
        return subprocess.run([vb.CANDI, "publish", *args], capture_output=True, text=True)
    r = publish(work, "-o", os.path.join(work, "nosite"))
    if r.returncode != 2 or work not in r.stderr or os.path.exists(os.path.join(work, "nosite")):
        failures.append("publish of a folder that is no archive: exit %d, %s" % (r.returncode, r.stderr.strip()))
    other = os.path.join(work, "other")
    os.mkdir(other)
    with open(os.path.join(other, "keep.txt"), "w") as f:
        f.write("mine")
    r = publish(archive, "-o", other)
    if r.returncode != 2 or other not in r.stderr or os.listdir(other) != ["keep.txt"]:
        failures.append("publish onto a folder that is not a site: exit %d, %s" % (r.returncode, r.stderr.strip()))
    locked = os.path.join(work, "locked")
    os.mkdir(locked)
    os.chmod(locked, stat.S_IRUSR | stat.S_IXUSR)
    try:
        r = publish(archive, "-o", os.path.join(locked, "site"))
        if os.geteuid() != 0 and (r.returncode != 2 or locked not in r.stderr or os.listdir(locked)):
            failures.append("publish into a read-only folder: exit %d, %s" % (r.returncode, r.stderr.strip()))
    finally:
        os.chmod(locked, stat.S_IRWXU)
    # Publishing again replaces a site, byte for byte the same.
    again = os.path.join(work, "again")
    vb.run("publish", archive, "-o", again, "-L", str(L), "--group-points", "40000", "--threads", "1")
    for root, _, files in os.walk(site):
        for name in files:
            rel = os.path.relpath(os.path.join(root, name), site)
            with open(os.path.join(site, rel), "rb") as a, open(os.path.join(again, rel), "rb") as b:
                if a.read() != b.read():
                    failures.append("publish on 1 thread and on all wrote different bytes in %s" % rel)
    return failures


if __name__ == "__main__":
    if find_chromium() is None:
        print("SKIP: chromium is not installed (scripts/deps.sh installs it)")
        sys.exit(0)
    vb.script_main(check, "candi-publish-")
