#!/usr/bin/env python3
"""Writes the test meshes made for qsil (CC0): icosphere.obj, a unit icosphere (3 subdivisions of
the icosahedron: 642 vertices, 1280 triangles, counter-clockwise seen from outside), and
two-spheres.obj, one OBJ holding two such spheres, of radius 0.5 centred at (-0.3, 0, 0) and of
radius 0.45 centred at (0.3, 0, 0), turned 0.3 rad about z (no symmetry puts an edge of one
exactly on an edge of the other): a self-intersecting mesh whose two parts cross along the circle
x = 0.0475 / 1.2, y^2 + z^2 = 0.25 - (x + 0.3)^2.
Usage: python3 tests/data/meshes/icosphere.py [OUT_DIR]   (default: this folder)"""
import math
import os
import sys


def icosphere(subdivisions):
    t = (1.0 + 5.0 ** 0.5) / 2.0
    verts = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
             (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    faces = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
             (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
             (6, 2, 10), (8, 6, 7), (9, 8, 1)]

    def unit(v):
        n = sum(c * c for c in v) ** 0.5
        return tuple(c / n for c in v)

    verts = [unit(v) for v in verts]
    for _ in range(subdivisions):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                verts.append(unit(tuple((x + y) / 2 for x, y in zip(verts[a], verts[b]))))
                cache[key] = len(verts) - 1
            return cache[key]

        new = []
        for a, b, c in faces:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            new += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        faces = new
    return verts, faces


def write(path, parts):
    with open(path, "w") as f:
        f.write("# written by tests/data/meshes/icosphere.py (qsil, CC0)\n")
        base = 0
        for verts, faces in parts:
            for v in verts:
                f.write("v %.9f %.9f %.9f\n" % v)
        for verts, faces in parts:
            for a, b, c in faces:
                f.write("f %d %d %d\n" % (a + base + 1, b + base + 1, c + base + 1))
            base += len(verts)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    verts, faces = icosphere(3)
    write(os.path.join(out, "icosphere.obj"), [(verts, faces)])
    c, s = math.cos(0.3), math.sin(0.3)
    parts = [([(0.5 * x - 0.3, 0.5 * y, 0.5 * z) for x, y, z in verts], faces),
             ([(0.45 * (c * x - s * y) + 0.3, 0.45 * (s * x + c * y), 0.45 * z) for x, y, z in verts], faces)]
    write(os.path.join(out, "two-spheres.obj"), parts)


if __name__ == "__main__":
    main()
