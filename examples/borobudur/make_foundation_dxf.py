#!/usr/bin/env python3
"""Writes foundation.dxf: the bundled example's four-layer section drawing (see foundation.md).

Run from anywhere: python3 examples/borobudur/make_foundation_dxf.py
The drawing is the project's own (not a copy of the paper's figure). Coordinates below are in
metres; the file stores millimetres ($INSUNITS = 4) so that the import's unit scaling is used.
Each layer uses a different entity type, so the example exercises every importer path.
"""
import os

MM = 1000.0

# Layer D: andesite with stone chips, the artificial hill (symmetric). LWPOLYLINE; the bulges
# round its shoulders (negative: the arc lies left of the drawing direction, i.e. above).
D = [(-80, -4, 0), (-62, 2, 0), (-30, 14, -0.15), (-14, 20, 0), (14, 20, -0.15), (30, 14, 0),
     (62, 2, 0), (80, -4, 0)]
# Layer C: soft volcanic tuff, natural hill (asymmetric). SPLINE through fit points.
C = [(-85, -10), (-60, -3), (-35, 5), (-15, 11), (3, 14), (20, 12), (45, 4), (70, -6), (85, -12)]
# Layer B: foam with andesite, natural hill (asymmetric). A chain of LINEs.
B = [(-85, -18), (-55, -10), (-25, -2), (-8, 3), (10, 1), (40, -7), (85, -20)]
# Layer A: andesite, natural hill (asymmetric). An old-style 2-D POLYLINE with VERTEXes.
A = [(-85, -28), (-50, -20), (-20, -12), (12, -8), (35, -13), (60, -22), (85, -30)]

# ACI colours as in the paper's Table 1: A blue, B yellow, C red, D green.
LAYERS = [("A", 5), ("B", 2), ("C", 1), ("D", 3)]


def num(v):
    return repr(float(v))


def pairs(*items):
    return "".join(f"{code}\n{value}\n" for code, value in items)


def xy(code, x, y):
    return pairs((code, num(x * MM)), (code + 10, num(y * MM)), (code + 20, "0.0"))


def drawing():
    out = pairs((999, "candi example: Borobudur foundation sections (examples/borobudur/foundation.md)"))
    out += pairs((0, "SECTION"), (2, "HEADER"), (9, "$ACADVER"), (1, "AC1015"),
                 (9, "$INSUNITS"), (70, "4"), (0, "ENDSEC"))
    out += pairs((0, "SECTION"), (2, "TABLES"), (0, "TABLE"), (2, "LAYER"), (70, str(len(LAYERS))))
    for name, colour in LAYERS:
        out += pairs((0, "LAYER"), (2, name), (70, "0"), (62, str(colour)), (6, "CONTINUOUS"))
    out += pairs((0, "ENDTAB"), (0, "ENDSEC"), (0, "SECTION"), (2, "ENTITIES"))
    out += pairs((0, "LWPOLYLINE"), (8, "D"), (90, str(len(D))), (70, "0"))
    for x, y, bulge in D:
        out += xy(10, x, y) + (pairs((42, num(bulge))) if bulge else "")
    out += pairs((0, "SPLINE"), (8, "C"), (70, "8"), (71, "3"), (72, "0"), (73, "0"),
                 (74, str(len(C))))
    for x, y in C:
        out += xy(11, x, y)
    for (x1, y1), (x2, y2) in zip(B, B[1:]):
        out += pairs((0, "LINE"), (8, "B")) + xy(10, x1, y1) + xy(11, x2, y2)
    out += pairs((0, "POLYLINE"), (8, "A"), (66, "1")) + xy(10, 0, 0) + pairs((70, "0"))
    for x, y in A:
        out += pairs((0, "VERTEX"), (8, "A")) + xy(10, x, y)
    out += pairs((0, "SEQEND"), (8, "A"), (0, "ENDSEC"), (0, "EOF"))
    return out


if __name__ == "__main__":
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "foundation.dxf")
    with open(path, "w", newline="\n") as f:
        f.write(drawing())
    print(path)
