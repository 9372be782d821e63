"""candi view's picking, measuring, clipping and sections in a real browser (Debian's chromium,
headless, driven through DevTools).

Usage: view_measure_test.py CANDI SOURCE_DIR   (ctest runs it; skips, saying why, without chromium)

The scene is the bundled foundation drawing made into points by `candi foundation` (four nested
layers, D on top) and packed by `candi pack`. Checks: a pick lists the shown layers under a pixel,
nearest first, and a pick where the top layer is hidden returns the visible layer's point; a pick
never takes clipped-away points; a mouse click in measure mode adds a point, and distance, height
difference and horizontal distance follow from the survey coordinates; a clipped converged frame
equals `candi render --clip-plane` bit for bit; a section exported from the page holds the shown
layers' lines. Point files viewed coloured by a field: the page's legend states the field, range
and grey counts, and a pick gives the picked point's value. Timeouts only catch hangs; no verdict depends on speed.
"""
import base64
import json
import math
import os
import sys
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import devtools  # noqa: E402
import view_browser_test  # noqa: E402
from view_browser_test import HANG, ViewerPage, run  # noqa: E402

TOP = {"eye": [0.5, -0.5, 120.0], "target": [0.5, 0.5, 0.0], "up": [0, 1, 0], "projection": "perspective",
       "fov_y_deg": 40, "near": 0.01}


class MeasureInBrowser(ViewerPage):
    POINTS = 300000

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        cls.names = cls.browser.evaluate("candiViewer.settings().layers.map((_, i) => i)")
        cls.browser.evaluate("candiViewer.setCamera(%s)" % json.dumps(TOP))

    def pick_centre(self):
        self.wait_converged()
        c = self.browser.evaluate("candiViewer.camera()")
        return self.browser.evaluate("candiViewer.pick(%f, %f)" % (c["width"] / 2, c["height"] / 2), await_promise=True)

    def layer_names(self):
        return self.browser.evaluate("(() => { const n = []; for (let i = 0; i < 4; ++i) "
                                     "n.push(document.querySelectorAll('#layers .name')[i].textContent); return n; })()")

    def test_1_pick_lists_shown_layers_and_skips_a_hidden_one(self):
        b = self.browser
        names = self.layer_names()
        self.assertEqual(names, ["foundation_A", "foundation_B", "foundation_C", "foundation_D"])
        b.evaluate("candiViewer.setSettings({layers: [1, 1, 1, 1], clip: []})")
        r = self.pick_centre()
        self.assertTrue(r["hit"], r)
        layers = [h["layer"] for h in r["hits"]]
        # Seen from above, the nested layers come in order: D over C over B over A.
        self.assertEqual(layers, [3, 2, 1, 0], r)
        depths = [h["depth"] for h in r["hits"]]
        self.assertEqual(depths, sorted(depths))
        self.assertAlmostEqual(r["point"][2], 20.0, delta=0.05)  # D's plateau, 20 m
        # D hidden (its box unticked as a user would): the pick returns C's point, never D's.
        b.evaluate("(() => { const e = document.getElementById('layer-visible-3'); e.checked = false; "
                   "e.dispatchEvent(new Event('input')); })()")
        self.assertEqual(b.evaluate("candiViewer.settings().layers"), [1, 1, 1, 0])
        r = self.pick_centre()
        self.assertEqual([h["layer"] for h in r["hits"]], [2, 1, 0], r)
        self.assertEqual(r["layer"], 2)
        self.assertLess(r["point"][2], 15.0)  # C peaks at 14 m
        b.evaluate("document.getElementById('layers-all').click()")

    def test_2_clipped_points_are_not_picked_and_the_frame_is_candi_renders(self):
        b = self.browser
        # Keep z <= 10: the centre's D (20 m) and C (~14 m) are cut away.
        plane = [0, 0, 10, 0, 0, -1]
        b.evaluate("candiViewer.setSettings({layers: [1, 1, 1, 1], clip: [%s]})" % json.dumps(plane))
        r = self.pick_centre()
        self.assertTrue(r["hit"])
        self.assertNotIn(3, [h["layer"] for h in r["hits"]])
        self.assertNotIn(2, [h["layer"] for h in r["hits"]])
        for h in r["hits"]:
            self.assertLessEqual(h["point"][2], 10.0)
        frame = self.wait_converged()
        view = os.path.join(self.dir, "view.json")
        with open(view, "w") as f:
            f.write(b.evaluate("candiViewer.viewJson()"))
        s = b.evaluate("candiViewer.settings()")
        reference = os.path.join(self.dir, "clipped.png")
        run("render", self.archive, "--view", view, "-L", str(s["repeat_level"]), "--seed", str(s["seed"]),
            "--background", ",".join(str(c) for c in s["background"]), "--brightness",
            "auto" if s["brightness"] == "auto" else str(s["brightness"]), "--clip-plane", ",".join(map(str, plane)),
            "-o", reference)
        with open(reference, "rb") as f:
            expected = devtools.decode_png(f.read())
        got = devtools.decode_png(base64.b64decode(b.evaluate("candiViewer.pngBase64()", await_promise=True)))
        self.assertEqual(got[:3], expected[:3])
        self.assertEqual(got[3], expected[3], "the clipped frame differs from candi render --clip-plane")
        self.assertEqual(frame["ensembles"], s["repeat_level"])
        b.evaluate("candiViewer.setSettings({clip: []})")

    def test_3_measure_by_clicks(self):
        b = self.browser
        b.evaluate("candiViewer.setSettings({layers: [1, 1, 1, 1], clip: []})")
        self.wait_converged()
        b.evaluate("document.getElementById('measure').checked = true")
        before = len(b.evaluate("candiViewer.measurements()"))
        for x, y in ((320, 240), (200, 300)):  # left of the panel
            b.mouse("mouseMoved", x, y, buttons=0, button="none")
            b.mouse("mousePressed", x, y)
            b.mouse("mouseReleased", x, y, buttons=0)
            b.wait_for("candiViewer.measurements().length > %d" % before, HANG, "a measured point")
            before += 1
        points = b.evaluate("candiViewer.measurements()")
        self.assertEqual(len(points), 2)
        a, c = points[0]["point"], points[1]["point"]
        seg = b.evaluate("candiViewer.segments()")[0]
        d = [c[k] - a[k] for k in range(3)]
        self.assertAlmostEqual(seg["distance"], math.sqrt(sum(v * v for v in d)), places=9)
        self.assertAlmostEqual(seg["horizontal"], math.hypot(d[0], d[1]), places=9)
        self.assertAlmostEqual(seg["dz"], d[2], places=9)
        self.assertGreater(seg["horizontal"], 1.0)
        # The first point is on D; "behind" steps to C's point under the same pixel.
        self.assertEqual(points[0]["layer"], "foundation_D")
        b.evaluate("candiViewer.stepBehind(0)")
        self.assertEqual(b.evaluate("candiViewer.measurements()")[0]["layer"], "foundation_C")
        csv = b.evaluate("candiViewer.measurementsCsv()").splitlines()
        self.assertEqual(csv[0], "point,layer,x,y,z,distance_m,horizontal_m,dz_m")
        self.assertEqual(len(csv), 3)
        # The overlay marks the point where it was clicked (the page projects as the server does).
        q = b.evaluate("candiViewer.project(candiViewer.measurements()[1].point)")
        self.assertAlmostEqual(q[0], 200, delta=3.5)
        self.assertAlmostEqual(q[1], 300, delta=3.5)
        b.evaluate("document.getElementById('measure').checked = false")

    def test_4_section_export_holds_the_shown_layers(self):
        b = self.browser
        b.evaluate("candiViewer.setSettings({layers: [1, 1, 0, 1], clip: []})")  # C hidden
        self.wait_converged()
        m = b.evaluate("candiViewer.exportSection({point: [0, 0, 0], normal: [0, 1, 0], thickness: 0.5})",
                       await_promise=True)
        self.assertEqual(m["type"], "section", m)
        names = [l["name"] for l in m["summary"]["layers"]]
        self.assertEqual(names, ["foundation_A", "foundation_B", "foundation_D"])
        for l in m["summary"]["layers"]:
            self.assertGreater(l["lines"], 0, l)
            self.assertGreater(l["length_m"], 150, l)  # each profile spans about 160-170 m
        self.assertIn("LWPOLYLINE", m["dxf"])
        self.assertNotIn("foundation_C", m["dxf"])
        self.assertTrue(m["svg"].startswith("<?xml"))
        self.assertTrue(base64.b64decode(m["png_base64"]).startswith(b"\x89PNG"))


class ColourByFieldInBrowser(ViewerPage):
    """`candi view FILE --colour-by distance`: the page's legend states the field, the range and
    the grey's counts, and a pick (and the measurement row) gives the picked point's value."""

    @classmethod
    def open_viewer(cls):
        # A 20 x 10 m sheet at survey coordinates whose distance is (x - 10) / 10: -1 west, +1
        # east; the first point has none (nan), the second lies outside the range.
        cls.origin = (416000.0, 9168000.0, 100.0)
        ply = os.path.join(cls.dir, "deviation.ply")
        rows = []
        for i in range(200):
            for j in range(100):
                x, y = i * 0.1 + 0.05, j * 0.1 + 0.05
                rows.append((x, y, (x - 10) / 10))
        rows[0] = (rows[0][0], rows[0][1], float("nan"))
        rows[1] = (rows[1][0], rows[1][1], 5.0)
        with open(ply, "w") as f:
            f.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty double x\nproperty double y\n"
                    "property double z\nproperty float scalar_distance\nend_header\n" % len(rows))
            for x, y, d in rows:
                f.write("%.3f %.3f %.3f %s\n" % (cls.origin[0] + x, cls.origin[1] + y, cls.origin[2], d))
        return view_browser_test.Viewer(ply, args=("--colour-by", "distance", "--field-range", "-1,1"))

    def test_legend_and_a_picked_value(self):
        b = self.browser
        legend = b.evaluate("(() => { const l = document.getElementById('legend'); return {hidden: l.hidden, "
                            "text: l.innerText, bar: getComputedStyle(l.querySelector('.scale')).backgroundImage}; })()")
        self.assertFalse(legend["hidden"], legend)
        self.assertIn("distance", legend["text"])
        for tick in ("-1", "0", "1", "1 outside", "1 without a value"):
            self.assertIn(tick, legend["text"])
        self.assertIn("linear-gradient", legend["bar"])
        # Straight down at x = 15 m (distance 0.5): the pick's value is the picked point's own.
        cx, cy = self.origin[0] + 15, self.origin[1] + 5
        top = {"eye": [cx, cy, self.origin[2] + 30], "target": [cx, cy, self.origin[2]], "up": [0, 1, 0],
               "projection": "perspective", "fov_y_deg": 40, "near": 0.01}
        b.evaluate("candiViewer.setCamera(%s)" % json.dumps(top))
        b.wait_for("(() => { const f = candiViewer.stats.lastFrame; return f && f.converged && "
                   "f.seq === candiViewer.viewSeq() ? f : null; })()", HANG, "convergence")
        c = b.evaluate("candiViewer.camera()")
        r = b.evaluate("candiViewer.pick(%f, %f)" % (c["width"] / 2, c["height"] / 2), await_promise=True)
        self.assertTrue(r["hit"], r)
        hit = r["hits"][0]
        expected = (hit["point"][0] - self.origin[0] - 10) / 10
        self.assertAlmostEqual(hit["value"], expected, delta=hit["value_half_width"] + 1e-3)
        self.assertAlmostEqual(hit["value"], 0.5, delta=0.05)
        self.assertLess(hit["value_half_width"], 0.01)
        # A measurement lists it beside the point.
        b.evaluate("candiViewer.measureAt(%f, %f)" % (c["width"] / 2, c["height"] / 2), await_promise=True)
        row = b.evaluate("document.querySelector('#measurements tbody tr').innerText")
        self.assertIn("distance 0.", row)


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit("usage: view_measure_test.py CANDI SOURCE_DIR")
    view_browser_test.CANDI = os.path.abspath(sys.argv[1])
    view_browser_test.SOURCE = os.path.abspath(sys.argv[2])
    if devtools.find_chromium() is None:
        print("SKIP: chromium is not installed (scripts/deps.sh installs it)")
        sys.exit(0)
    unittest.main(argv=[sys.argv[0], "-v"])
