#!/usr/bin/env python3
"""Proves a refactoring kept what candi says about bad input: the same exit codes and messages.

  scripts/same_messages.py record BUILD_DIR OUT_FILE
      Runs BUILD_DIR's candi on the bad-input corpus below and writes one JSON record per case:
      the command, its exit code and its stderr (the corpus folder's path normalised).
  scripts/same_messages.py compare OLD_FILE NEW_FILE
      Lists every case whose exit code or message differs. Exit 0 when none does.

The corpus: every file of fuzz/corpus/ and fuzz/regressions/ given to the command that reads its
format (point files to `candi info`, drawings to `candi foundation`, scenes to `candi build`, an
archive's bytes as a render archive), and the command line's bad values (the rows of
tests/cli_errors_test.cc and the render settings every command shares: L, seed, point size,
brightness, size, background), each on small valid inputs the script writes itself.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

SOURCE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# Point files for `candi info`, by the corpus folder; other folders map to other commands.
READERS = {"ply": ".ply", "las": ".las", "laz": ".laz", "e57": ".e57", "xyz": ".xyz"}


def write_inputs(d):
    with open(os.path.join(d, "in.ply"), "w") as f:
        f.write("ply\nformat ascii 1.0\nelement vertex 200\nproperty double x\nproperty double y\n"
                "property double z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n")
        for i in range(200):
            f.write("%g %g %g %d 80 160\n" % (0.01 * (i % 20), 0.01 * (i // 20), 0.001 * i, i))
    with open(os.path.join(d, "scene.json"), "w") as f:
        json.dump({"candi_scene": 1, "render": {"repeat_level": 2, "width": 32, "height": 24},
                   "layers": [{"name": "a", "kind": "points", "file": "in.ply"}]}, f)


def cases(d):
    """(name, argv) of every case; {D} is the corpus folder."""
    out = []
    for root in ("fuzz/corpus", "fuzz/regressions"):
        base = os.path.join(SOURCE, root)
        if not os.path.isdir(base):
            continue
        for kind in sorted(os.listdir(base)):
            for name in sorted(os.listdir(os.path.join(base, kind))):
                src = os.path.join(base, kind, name)
                if not os.path.isfile(src):
                    continue
                tag = "%s/%s/%s" % (root, kind, name)
                if kind in READERS:
                    dst = os.path.join(d, "corpus_" + kind + "_" + name + READERS[kind])
                    shutil.copyfile(src, dst)
                    out.append((tag, ["info", dst]))
                elif kind == "dxf":
                    dst = os.path.join(d, "corpus_" + name + ".dxf")
                    shutil.copyfile(src, dst)
                    out.append((tag, ["foundation", dst, "-o", os.path.join(d, "f.ply"), "--count", "100",
                                      "--no-check"]))
                elif kind == "scene":
                    dst = os.path.join(d, "corpus_scene_" + name + ".json")
                    shutil.copyfile(src, dst)
                    out.append((tag, ["build", dst, "-o", os.path.join(d, "b_" + name)]))
                elif kind == "archive":
                    arc = os.path.join(d, "corpus_archive_" + name)
                    os.makedirs(arc, exist_ok=True)
                    shutil.copyfile(src, os.path.join(arc, "manifest.json"))
                    out.append((tag, ["render", arc, "-o", os.path.join(d, "a.png")]))
    ply, png = os.path.join(d, "in.ply"), os.path.join(d, "o.png")
    scene = os.path.join(d, "scene.json")
    bad_values = [
        ["render", ply, "-o", png, "-L", "0"], ["render", ply, "-o", png, "-L", "100001"],
        ["render", ply, "-o", png, "--point-size", "0.5"], ["render", ply, "-o", png, "--point-size", "65"],
        ["render", ply, "-o", png, "--brightness", "0"], ["render", ply, "-o", png, "--brightness", "abc"],
        ["render", ply, "-o", png, "--brightness", "101"], ["render", ply, "-o", png, "--size", "0x10"],
        ["render", ply, "-o", png, "--background", "1,2"], ["render", ply, "-o", png, "--opaque", "--alpha", "0.5"],
        ["render", ply, "-o", png, "--alpha", "1.5"], ["render", ply, "-o", png, "--view", os.path.join(d, "none.json")],
        ["render", ply, "-o", png, "--mode", "fast"], ["render", os.path.join(d, "missing.ply"), "-o", png],
        ["section", ply, "--plane", "0,0,0,1,0,0", "--thickness", "0.1", "-o", os.path.join(d, "s"), "-L", "0"],
        ["section", ply, "--plane", "0,0,0,1,0,0", "--thickness", "0.1", "-o", os.path.join(d, "s"), "-L", "20000"],
        ["section", ply, "--plane", "0,0,0,1,0,0", "--thickness", "0.1", "-o", os.path.join(d, "s"),
         "--point-size", "100"],
        ["opacity", ply, os.path.join(d, "o.ply"), "--alpha", "0.5", "--repeat-level", "0", "--image-size", "64"],
        ["opacity", ply, os.path.join(d, "o.ply"), "--alpha", "2", "--repeat-level", "4", "--image-size", "64"],
        ["publish", os.path.join(d, "nothing"), "-o", os.path.join(d, "site")],
        ["publish", d, "-o", os.path.join(d, "site")],
        ["pack", ply, "-o", os.path.join(d, "arc"), "--chunk-points", "1"],
        ["build", os.path.join(d, "missing.json"), "-o", os.path.join(d, "b")],
        ["build", scene, "-o", os.path.join(d, "b"), "--threads", "999"],
        ["info", os.path.join(d, "in.ply") + ".nope"],
        ["convert", ply, os.path.join(d, "o.ply"), "--precision", "half"],
        ["foundation", os.path.join(d, "missing.dxf"), "-o", os.path.join(d, "f.ply")],
        ["view", ply, "--port", "70000"],
    ]
    for argv in bad_values:
        out.append(("args: " + " ".join(a.replace(d, "{D}") for a in argv), argv))
    # A scene whose render settings are out of range (the scene's parser).
    for key, value in (("repeat_level", 0), ("brightness", 0), ("brightness", 500), ("brightness", "bright"),
                       ("width", 0), ("background", [1, 2])):
        path = os.path.join(d, "scene_%s_%s.json" % (key, re.sub(r"\W", "_", str(value))))
        with open(path, "w") as f:
            json.dump({"candi_scene": 1, "render": {key: value},
                       "layers": [{"name": "a", "kind": "points", "file": "in.ply"}]}, f)
        out.append(("scene render %s = %s" % (key, json.dumps(value)),
                    ["build", path, "-o", os.path.join(d, "b_render")]))
    return out


def record(build, out_file):
    candi = os.path.join(os.path.abspath(build), "apps", "candi")
    d = tempfile.mkdtemp(prefix="candi-messages-")
    try:
        write_inputs(d)
        results = []
        for name, argv in cases(d):
            try:
                p = subprocess.run([candi, *argv], capture_output=True, text=True, timeout=600, cwd=d)
                code, err = p.returncode, p.stderr
            except subprocess.TimeoutExpired:
                code, err = "timeout", ""
            err = err.replace(d, "{D}")
            # Progress lines and run times are not messages.
            err = "\n".join(l for l in err.splitlines() if not re.search(r"\d+(\.\d+)? s\b|points/s|^\S+: \d+%", l))
            results.append({"case": name, "exit": code, "stderr": err})
            print("%-70s exit %s" % (name[:70], code), file=sys.stderr)
    finally:
        shutil.rmtree(d, ignore_errors=True)
    with open(out_file, "w") as f:
        json.dump(results, f, indent=1)


def compare(old_file, new_file):
    with open(old_file) as f:
        old = {r["case"]: r for r in json.load(f)}
    with open(new_file) as f:
        new = {r["case"]: r for r in json.load(f)}
    bad = 0
    for case in sorted(set(old) | set(new)):
        a, b = old.get(case), new.get(case)
        if a is None or b is None:
            print(("only in new: " if a is None else "only in old: ") + case)
            bad += 1
        elif a["exit"] != b["exit"] or a["stderr"] != b["stderr"]:
            bad += 1
            print("differs: %s\n  old exit %s: %s\n  new exit %s: %s" % (case, a["exit"], a["stderr"].strip()[-400:],
                                                                       b["exit"], b["stderr"].strip()[-400:]))
    print("%d cases; %d differ" % (len(set(old) | set(new)), bad))
    return 0 if bad == 0 else 1


def main(argv):
    if len(argv) == 3 and argv[0] == "record":
        record(argv[1], argv[2])
        return 0
    if len(argv) == 3 and argv[0] == "compare":
        return compare(argv[1], argv[2])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
