#!/usr/bin/env python3
"""Proves a refactoring changed no behaviour: the same commands give the same bytes.

  scripts/same_bytes.py record BUILD_DIR OUT_DIR [--no-full-demo] [--docs PAGE ...]
      Runs, with BUILD_DIR's candi, `candi demo --quick`, `candi demo` (the full demo) and every
      ```sh block of every page of docs/ (through candi_docs_runner, each page's working directory
      kept), and keeps every file they write under OUT_DIR (demo_quick/, demo/, docs/<page>/).
  scripts/same_bytes.py compare OLD_DIR NEW_DIR
      Compares two recorded trees file by file and lists every file that is missing on one side or
      differs. Exit 0 when the outputs are the same bytes, 1 otherwise.

What is not behaviour, and so is normalised before comparing (each rule is printed by compare):
  - the docs runner's random working-directory names, in every file (outputs that record an
    absolute input path name them); PNG chunks compare without their CRCs (which cover such
    names). Record both trees at the same OUT_DIR (move the first aside before recording the
    second): hashes over text that names the folder (a scene's key) match only then;
  - in JSON files, values under keys that hold run times ("seconds", "*_seconds", "timings",
    "stages" of section.json, "total"), which differ between any two runs;
  - timings.json (a build's run times, kept apart from archive.json for this reason), logs (the
    runner's block logs, COLMAP's logs) and the runner's block scripts.
Files known to differ between two runs of the same binary are compared and listed apart, as
"known to vary", and do not fail the comparison (KNOWN_TO_VARY names each and why).

The demo names examples/ by the absolute path of the source tree its candi was built from, and
the build's checkpoint keys hash that text: record two builds whose source trees sit at one path
(or build the old one's pipeline/demo_site.cc with -DCANDI_SOURCE_DIR set to the new tree).
"""
import json
import os
import re
import subprocess
import sys
import time

SOURCE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TIMING_KEYS = re.compile(r"(^|_)(seconds|timings|ms|elapsed|stages)$|^total$|^time")
SKIP_FILES = re.compile(r"(^|/)(timings\.json|block_line\d+\.sh|[^/]*\.log|[^/]*\.log\.[A-Z]+\.[0-9.-]+)$")
# (pattern, why): files that differ between two runs of one binary on the same input.
KNOWN_TO_VARY = [
    (re.compile(r"(^|/)database\.db$"),
     "COLMAP's SQLite database: its pages follow the order the extractor's threads finish"),
    (re.compile(r"\.ckpt$"),
     "libtorch's optimizer state: keyed by the tensors' addresses in memory"),
    (re.compile(r"\.e57$"),
     "an E57 file's GUIDs, new on every write"),
]
RECORDED_AT = ".recorded_at"  # the folder the recording was made in (outputs name it)
RUNNER_DIR = re.compile(r"candi-docs-[A-Za-z0-9]{6}")
RUNNER_DIR_BYTES = re.compile(rb"candi-docs-[A-Za-z0-9]{6}")


def run(cmd, env=None, log=None):
    start = time.time()
    print("+ " + " ".join(cmd), file=sys.stderr, flush=True)
    with open(log, "w") if log else open(os.devnull, "w") as out:
        code = subprocess.call(cmd, env=env, stdout=out, stderr=subprocess.STDOUT)
    print(f"  exit {code}, {time.time() - start:.0f} s", file=sys.stderr, flush=True)
    return code


def record(build, out, full_demo, pages):
    build = os.path.abspath(build)
    out = os.path.abspath(out)
    candi = os.path.join(build, "apps", "candi")
    runner = os.path.join(build, "tests", "candi_docs_runner")
    if os.path.exists(out):
        sys.exit(f"same_bytes: {out} exists; record into a new folder")
    os.makedirs(out)
    with open(os.path.join(out, RECORDED_AT), "w") as f:
        f.write(out)
    failures = []
    if run([candi, "-q", "demo", "--quick", "-o", os.path.join(out, "demo_quick")]) != 0:
        failures.append("demo --quick")
    if full_demo and run([candi, "-q", "demo", "-o", os.path.join(out, "demo")]) != 0:
        failures.append("demo")
    if not pages:
        for root, _, files in os.walk(os.path.join(SOURCE, "docs")):
            for f in files:
                if f.endswith(".md"):
                    pages.append(os.path.relpath(os.path.join(root, f), SOURCE))
    for page in sorted(pages):
        work = os.path.join(out, "docs", page.replace("/", "_"))
        os.makedirs(work)
        env = dict(os.environ, TMPDIR=work, CANDI_DOCS_KEEP="1", CANDI_DOCS_TIMEOUT="1200")
        code = run([runner, SOURCE, os.path.dirname(candi), page], env=env,
                   log=os.path.join(out, "docs", page.replace("/", "_") + ".log"))
        if code not in (0, 77):
            failures.append(page)
    # The links the runner makes to examples/ and the shared data are inputs, not outputs.
    for root, dirs, files in os.walk(out):
        for name in list(dirs) + files:
            p = os.path.join(root, name)
            if os.path.islink(p):
                os.unlink(p)
                if name in dirs:
                    dirs.remove(name)
    if failures:
        sys.exit("same_bytes: failed: " + ", ".join(failures))


def normalise_json(value):
    if isinstance(value, dict):
        return {k: ("<time>" if TIMING_KEYS.search(k) else normalise_json(v)) for k, v in value.items()}
    if isinstance(value, list):
        return [normalise_json(v) for v in value]
    return value


def png_chunks(data):
    """A PNG's chunks without their CRCs (text chunks are normalised like text files)."""
    out, pos = [data[:8]], 8
    while pos + 8 <= len(data):
        length = int.from_bytes(data[pos:pos + 4], "big")
        out.append(data[pos + 4:pos + 8] + data[pos + 8:pos + 8 + length])
        pos += 12 + length
    return b"\n".join(out)


def content(path, root):
    with open(path, "rb") as f:
        data = f.read()
    data = data.replace(root.encode(), b"<OUT>" + b"_" * (len(root) - 5))
    data = RUNNER_DIR_BYTES.sub(b"candi-docs-XXXXXX", data)
    if data.startswith(b"\x89PNG"):
        return png_chunks(data)
    if b"\0" in data[:65536]:
        return data
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return data
    if path.endswith(".json"):
        try:
            return json.dumps(normalise_json(json.loads(text)), sort_keys=True).encode()
        except ValueError:
            pass
    return text.encode()


def files(root):
    found = {}
    for dirpath, _, names in os.walk(root):
        for name in names:
            p = os.path.join(dirpath, name)
            if os.path.islink(p) or name == RECORDED_AT:
                continue
            rel = RUNNER_DIR.sub("candi-docs-XXXXXX", os.path.relpath(p, root))
            if rel.endswith(".log") and rel.count("/") == 1 or SKIP_FILES.search(rel):
                continue
            found[rel] = p
    return found


def recorded_at(tree):
    try:
        with open(os.path.join(tree, RECORDED_AT)) as f:
            return f.read().strip()
    except OSError:
        return tree


def compare(old, new):
    old, new = os.path.abspath(old), os.path.abspath(new)
    a, b = files(old), files(new)
    root_a, root_b = recorded_at(old), recorded_at(new)
    print("normalised: absolute paths of the recording; JSON keys matching " + TIMING_KEYS.pattern +
          "; files matching " + SKIP_FILES.pattern + " are skipped")
    bad = 0
    varied = {}
    for rel in sorted(set(a) | set(b)):
        if rel not in a or rel not in b:
            print(("only in new: " if rel in b else "only in old: ") + rel)
            bad += 1
            continue
        ca, cb = content(a[rel], root_a), content(b[rel], root_b)
        if ca != cb:
            why = next((w for pattern, w in KNOWN_TO_VARY if pattern.search(rel)), None)
            if why:
                varied.setdefault(why, []).append(rel)
                continue
            print(f"differs: {rel} ({len(ca)} vs {len(cb)} bytes)")
            bad += 1
    for why, rels in varied.items():
        print(f"known to vary ({why}): " + ", ".join(rels))
    print(f"{len(a)} files in old, {len(b)} in new; {bad} differ or are missing")
    return 0 if bad == 0 else 1


def main(argv):
    if len(argv) >= 3 and argv[0] == "record":
        rest = argv[3:]
        full = "--no-full-demo" not in rest
        pages = rest[rest.index("--docs") + 1:] if "--docs" in rest else []
        record(argv[1], argv[2], full, pages)
        return 0
    if len(argv) == 3 and argv[0] == "compare":
        return compare(argv[1], argv[2])
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
