#!/usr/bin/env python3
"""Writes ring.obj, made for qsil (CC0): a thin torus, a wire ring of major radius 1 and tube radius
0.05 about the y axis, 128 segments around the ring and 12 around the tube (1536 vertices, 3072
triangles, counter-clockwise seen from outside, positions only): the thin, curved object of the
stability scene `thin-metal`, whose tube is seen at grazing angles along both of its outlines.
Usage: python3 scenes/stability/meshes/ring.py [OUT_DIR]   (default: this folder)"""
import math
import os
import sys

MAJOR, MINOR, RING, TUBE = 1.0, 0.05, 128, 12


def ring():
    verts, faces = [], []
    for i in range(RING):
        a = 2 * math.pi * i / RING
        for j in range(TUBE):
            b = 2 * math.pi * j / TUBE
            r = MAJOR + MINOR * math.cos(b)
            verts.append((r * math.cos(a), MINOR * math.sin(b), -r * math.sin(a)))
    for i in range(RING):
        for j in range(TUBE):
            p, q = i * TUBE + j, i * TUBE + (j + 1) % TUBE
            pn, qn = ((i + 1) % RING) * TUBE + j, ((i + 1) % RING) * TUBE + (j + 1) % TUBE
            faces += [(p, pn, qn), (p, qn, q)]
    return verts, faces


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
    verts, faces = ring()
    with open(os.path.join(out, "ring.obj"), "w") as f:
        f.write("# ring: a thin torus (major radius %g, tube radius %g), written for qsil, CC0\n" % (MAJOR, MINOR))
        f.write("# %d vertices, %d triangles; positions only, 1-based indices, CCW = outward\n" % (len(verts), len(faces)))
        for v in verts:
            f.write("v %.9g %.9g %.9g\n" % v)
        for t in faces:
            f.write("f %d %d %d\n" % tuple(k + 1 for k in t))


if __name__ == "__main__":
    main()
