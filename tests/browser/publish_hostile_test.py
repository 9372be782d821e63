#!/usr/bin/python3
"""A published site against a damaged or hostile site.json and data, in Debian's chromium
(headless, software WebGL2), served by `python3 -m http.server`.

Each case is a copy of a real site (candi publish of the bundled foundation) with one thing
broken, as a careful user or a hostile host would break it:
- a page claiming 2^31 points; a consistent index whose pages are larger than the memory budget;
- repeat_level 10^9; repeat_level twice the pages; a missing `groups`; a string `chunks`;
- a group range past the chunks; a 1e309 box; a null step; fields of 60 bits;
- `views: null`; one bad provenance entry; a legend that is not one;
- memory_mb=-1 and memory_mb=1e-9 in the address;
- a gzip bomb: a 1 MB page that inflates to 1 GiB, its byte count fixed in site.json.
For each: the page names the bad item in a readable line (no raw JavaScript message, no
uncaught exception), draws what is valid (an image with points in it) unless nothing can be
drawn (then it says why in the status), never stalls, and never says "converged" while pages
are missing or failed. For the bomb, the renderer's peak memory (VmHWM of chromium's renderer
processes) stays within the site's budget plus a stated slack above the same site intact.
Usage: publish_hostile_test.py CANDI SOURCE_DIR"""
import base64
import copy
import gzip
import json
import os
import re
import shutil
import sys
import time
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import view_browser_test as vb  # noqa: E402
from devtools import Browser, find_chromium  # noqa: E402
from publish_browser_test import Served  # noqa: E402

# What a readable message never holds: JavaScript's own words for a program's fault.
RAW = re.compile(r"Cannot read properties|is not a function|is not iterable|TypeError|RangeError|undefined|NaN")
SLACK_MB = 160  # above the intact site's peak: the budget's share plus one inflated piece and noise

M64 = (1 << 64) - 1


def mix64(z):
    z = (z + 0x9e3779b97f4a7c15) & M64
    z = ((z ^ (z >> 30)) * 0xbf58476d1ce4e5b9) & M64
    z = ((z ^ (z >> 27)) * 0x94d049bb133111eb) & M64
    return z ^ (z >> 31)


def slice_points(count, first, L, seed, k):
    """render/archive.cc's EnsembleSlices: the points of slice k of a chunk at (seed, L)."""
    r = mix64(mix64(seed ^ mix64(0x5EED511CE)) ^ first) % L
    s = (k + r) % L
    return (s + 1) * count // L - s * count // L


def bomb(size):
    """A gzip stream of `size` zero bytes, at deflate's best ratio (~1030:1)."""
    c = zlib.compressobj(9, zlib.DEFLATED, 31)
    block = bytes(1 << 24)
    parts = [c.compress(block) for _ in range(size >> 24)]
    parts.append(c.flush())
    return b"".join(parts)


def renderer_peak_mb(browser):
    """The largest VmHWM (peak resident memory) of chromium's renderer processes, in MB."""
    peak = 0
    for pid in os.listdir("/proc"):
        if not pid.isdigit():
            continue
        try:
            with open("/proc/%s/cmdline" % pid, "rb") as f:
                cmd = f.read()
            if b"--type=renderer" not in cmd or browser.profile.encode() not in cmd and \
                    not _descends(int(pid), browser.process.pid):
                continue
            with open("/proc/%s/status" % pid) as f:
                for line in f:
                    if line.startswith("VmHWM:"):
                        peak = max(peak, int(line.split()[1]) / 1024)
        except OSError:
            continue
    return peak


def _descends(pid, ancestor):
    for _ in range(8):
        try:
            with open("/proc/%d/stat" % pid) as f:
                pid = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            return False
        if pid == ancestor:
            return True
        if pid <= 1:
            return False
    return False


def make_case(base, work, name, change):
    """A copy of the site `base` as `name`, site.json changed by change(index, folder) (which
    returns the new index, or a text to write as it is)."""
    folder = os.path.join(work, "cases", name)
    shutil.copytree(base, folder)
    with open(os.path.join(base, "site.json")) as f:
        index = json.load(f)
    out = change(index, folder)
    with open(os.path.join(folder, "site.json"), "w") as f:
        f.write(out if isinstance(out, str) else json.dumps(out))
    return name


def open_case(browser, served, name, query=""):
    browser.events.clear()
    browser.call("Page.navigate", url=served.url(name + "/" + query))
    time.sleep(0.5)
    browser.wait_for("window.candiViewer && document.readyState === 'complete'", 120, name + ": the page")
    end = time.time() + 240
    while time.time() < end:
        state = browser.evaluate("(() => { const v = window.candiViewer; const p = v.progress ? v.progress() : null; "
                                 "return {settled: !!(p && p.settled && !v.dirty()), status: v.status ? v.status() : "
                                 "document.getElementById('status').textContent, errors: v.errors()}; })()")
        if state["settled"] or "cannot be drawn" in state["status"]:
            time.sleep(0.3)
            return state
        time.sleep(0.2)
    raise AssertionError("%s: the page did not settle: %s" % (name, state))


def image_has_points(browser):
    try:
        rgb = base64.b64decode(browser.evaluate("window.candiViewer.imageRgb()"))
    except RuntimeError:
        return False
    return any(rgb)


def check(work):
    failures = []
    archive = vb.foundation_archive(work, 120000)
    base = os.path.join(work, "base")
    vb.run("publish", archive, "-o", base, "-L", "8", "--group-points", "20000")
    with open(os.path.join(base, "site.json")) as f:
        index = json.load(f)
    d = index["data"]
    groups, chunks, L, seed = d["groups"], d["chunks"], d["repeat_level"], d["seed"]
    F = {n: i for i, n in enumerate(d["chunk_fields"])}
    if len(groups) < 4:
        return ["the base site has %d groups; the cases want several" % len(groups)]

    def with_data(**kw):
        def change(ix, _):
            ix["data"].update(kw)
            return ix
        return change

    def chunk_field(c, field, value):
        def change(ix, _):
            ix["data"]["chunks"][c][F[field]] = value
            return ix
        return change

    def claim_2_31(ix, _):
        ix["data"]["groups"][1]["pages"][0][1] = 2 ** 31
        return ix

    def larger_than_budget(ix, _):
        # A consistent index: chunk 0 of group 2 holds 2^24 points, its pages the slices of that
        # (2 M points each), more than ?memory_mb=16 (1 M points) holds.
        g = ix["data"]["groups"][2]
        c0 = g["chunks"][0]
        ix["data"]["chunks"][c0][F["count"]] = 1 << 24
        for k in range(L):
            points = sum(slice_points(ix["data"]["chunks"][c][F["count"]], ix["data"]["chunks"][c][F["first"]], L,
                                      seed, k) for c in range(g["chunks"][0], g["chunks"][1]))
            g["pages"][k][1] = points
        return ix

    def past_the_chunks(ix, _):
        ix["data"]["groups"][-1]["chunks"] = [ix["data"]["groups"][-1]["chunks"][0], len(chunks) + 5]
        return ix

    def box_1e309(ix, _):
        ix["data"]["chunks"][3][F["max_x"]] = 123456789.25  # a value found once, then made 1e309
        return json.dumps(ix).replace("123456789.25", "1e309")

    def views_null(ix, _):
        ix["scene"]["views"] = None
        return ix

    def bad_provenance(ix, _):
        ix["scene"]["provenance"] = {"licence": "CC0", "layers": [None, {"name": "hill", "scanned": False,
                                                                       "sources": [{"file": "hill.dxf"}, 7]}],
                                     "annotations": [{"title": "ok", "position": [0, 0, 0]}, {"title": 3}]}
        return ix

    def bad_legend(ix, _):
        ix["scene"]["legend"] = {"field": "distance", "lo": 1, "hi": 0}
        return ix

    def no_groups(ix, _):
        del ix["data"]["groups"]
        return ix

    first_group_chunk = groups[1]["chunks"][0]
    cases = [
        # (name, change, query, what the errors must name, drawable)
        ("claim_2_31", claim_2_31, "", "data.groups[1] pages[0] claims 2147483648 points", True),
        ("over_budget", larger_than_budget, "?memory_mb=16", "data/2/: 8 pages", True),
        ("repeat_1e9", with_data(repeat_level=10 ** 9), "", "data.repeat_level 1000000000", False),
        ("repeat_twice", with_data(repeat_level=2 * L), "", "holds %d pages; data.repeat_level says %d" % (L, 2 * L),
         False),
        ("no_groups", no_groups, "", "data.groups is not a list", False),
        ("string_chunks", with_data(chunks="many"), "", "data.chunks is not a list", False),
        ("past_the_chunks", past_the_chunks, "", "data.groups[%d] chunks" % (len(groups) - 1), True),
        ("box_1e309", box_1e309, "", "data.chunks[3].max_x", True),
        ("null_step", chunk_field(first_group_chunk, "step_y", None), "", "data.chunks[%d].step_y" % first_group_chunk,
         True),
        ("bits_60", chunk_field(first_group_chunk, "bits_x", 20), "", "data.chunks[%d].bits_x" % first_group_chunk,
         True),
        ("views_null", views_null, "", "scene.views is not a list", True),
        ("bad_provenance", bad_provenance, "", "scene.provenance.layers[0]", True),
        ("bad_legend", bad_legend, "", "scene.legend", True),
        ("memory_negative", lambda ix, _: ix, "?memory_mb=-1", "memory_mb=-1 is not in [16, 65536]", True),
        ("memory_tiny", lambda ix, _: ix, "?memory_mb=1e-9", "memory_mb=1e-9 is not in [16, 65536]", True),
    ]
    for name, change, _, _, _ in cases:
        make_case(base, work, name, change)

    # The bomb's site: L = 1 and groups of ~260 k points (2 MB of planes a page), so that 1 MB of
    # gzip is a size site.json may state for one; the bomb replaces group 0's page, its byte count
    # fixed; group 1 is intact.
    big = os.path.join(work, "big")
    os.makedirs(big)
    big_archive = vb.foundation_archive(big, 400000)
    big_site = os.path.join(work, "cases", "big_intact")
    vb.run("publish", big_archive, "-o", big_site, "-L", "1", "--group-points", "300000")
    payload = bomb(1 << 30)
    print("gzip bomb: %d bytes that inflate to %d" % (len(payload), 1 << 30))

    def the_bomb(ix, folder):
        with open(os.path.join(folder, "data", "0", "0.bin"), "wb") as f:
            f.write(payload)
        ix["data"]["groups"][0]["pages"][0][0] = len(payload)
        return ix
    make_case(big_site, work, "bomb", the_bomb)
    with open(os.path.join(big_site, "site.json")) as f:
        big_index = json.load(f)
    page0 = big_index["data"]["groups"][0]["pages"][0]
    if not len(payload) <= 8 * page0[1]:
        failures.append("the bomb (%d bytes) is larger than a page of %d points may be: the test cannot feed it"
                        % (len(payload), page0[1]))

    served = Served(os.path.join(work, "cases"))
    browser = Browser(480, 360, webgl=True)
    try:
        browser.call("Runtime.enable")
        for name, _, query, named, drawable in cases:
            state = open_case(browser, served, name, query)
            thrown = [e for e in browser.events if e.get("method") == "Runtime.exceptionThrown"]
            errors = state["errors"]
            print("%s: status %r; %d messages: %s" % (name, state["status"][:120], len(errors), " | ".join(errors)[:400]))
            if thrown:
                failures.append("%s: uncaught exceptions: %s" % (name, json.dumps(thrown[0])[:400]))
            if not any(named in e for e in errors):
                failures.append("%s: no message names %r: %s" % (name, named, errors))
            raw = [e for e in errors if RAW.search(e)]
            if raw:
                failures.append("%s: raw JavaScript messages: %s" % (name, raw))
            if len(errors) > 8:
                failures.append("%s: %d messages for one fault (one line per bad item wanted)" % (name, len(errors)))
            shown = browser.evaluate("document.getElementById('errors').textContent")
            if named not in shown and not (not drawable and named in state["status"]):
                failures.append("%s: the page does not show %r: %r" % (name, named, shown))
            if drawable:
                if not image_has_points(browser):
                    failures.append("%s: nothing drawn; the valid part should be" % name)
                progress = browser.evaluate("window.candiViewer.progress()")
                if progress["missing"] and "converged" in state["status"]:
                    failures.append("%s: says converged with %s missing: %r" % (name, progress["missing"], state["status"]))
            elif "cannot be drawn" not in state["status"]:
                failures.append("%s: the status does not say the site cannot be drawn: %r" % (name, state["status"]))
    finally:
        browser.close()

    # The bomb: in a fresh browser each, the intact site and the bombed one; the renderer's peak.
    peaks = {}
    for name in ("big_intact", "bomb"):
        browser = Browser(480, 360, webgl=True)
        try:
            browser.call("Runtime.enable")
            start = time.time()
            state = open_case(browser, served, name)
            peaks[name] = renderer_peak_mb(browser)
            print("%s: settled in %.1f s, renderer peak %.0f MB; status %r; errors %s"
                  % (name, time.time() - start, peaks[name], state["status"][:100], state["errors"]))
            if name == "bomb":
                if not any("data/0/0.bin" in e and "inflating stopped" in e for e in state["errors"]):
                    failures.append("the bomb is not named as one: %s" % state["errors"])
                if "converged" in state["status"]:
                    failures.append("the bombed site says converged: %r" % state["status"])
                if not image_has_points(browser):
                    failures.append("the bombed site drew nothing of its intact pages")
            elif state["errors"]:
                failures.append("the intact big site has errors: %s" % state["errors"])
        finally:
            browser.close()
    budget = big_index["data"]["memory_mb"]
    print("renderer peak: intact %.0f MB, bomb %.0f MB (allowed: + the budget %d MB + %d MB slack; the whole "
          "inflation would be %d MB)" % (peaks["big_intact"], peaks["bomb"], budget, SLACK_MB, 1 << 10))
    if peaks["bomb"] > peaks["big_intact"] + budget + SLACK_MB:
        failures.append("the bomb took the renderer to %.0f MB (intact: %.0f MB)" % (peaks["bomb"], peaks["big_intact"]))
    served.close()
    return failures


if __name__ == "__main__":
    if find_chromium() is None:
        print("SKIP: chromium is not installed (scripts/deps.sh installs it)")
        sys.exit(0)
    sys.exit(vb.script_main(check, "candi-publish-hostile-"))
