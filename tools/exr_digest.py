#!/usr/bin/env python3
"""Prints a SHA-256 prefix of an OpenEXR file's pixel data and header, without the attributes
that change from run to run (qsil:seconds, the wall time). Scan-line files only (what qsil writes).

Usage: exr_digest.py FILE.exr ...   (standard library only; OpenEXR 2.0 file layout)
"""
import hashlib
import struct
import sys

VOLATILE = {b"qsil:seconds"}


def digest(path):
    data = open(path, "rb").read()
    if data[:4] != b"\x76\x2f\x31\x01":
        sys.exit(f"{path}: not an OpenEXR file")
    if data[5] & 0x02:
        sys.exit(f"{path}: tiled OpenEXR files are not supported")
    h = hashlib.sha256()
    pos = 8
    attributes = {}
    while data[pos] != 0:
        name_end = data.index(b"\0", pos)
        type_end = data.index(b"\0", name_end + 1)
        name = data[pos:name_end]
        (size,) = struct.unpack_from("<i", data, type_end + 1)
        value = data[type_end + 5:type_end + 5 + size]
        attributes[name] = value
        if name not in VOLATILE:
            h.update(data[pos:type_end + 5 + size])
        pos = type_end + 5 + size
    pos += 1
    _, y_min, _, y_max = struct.unpack("<iiii", attributes[b"dataWindow"])
    lines_per_chunk = {0: 1, 1: 1, 2: 1, 3: 16, 4: 32, 5: 16, 6: 32, 7: 256, 8: 256, 9: 32}[attributes[b"compression"][0]]
    chunks = (y_max - y_min + lines_per_chunk) // lines_per_chunk
    h.update(data[pos + 8 * chunks:])  # the chunks, after the offset table (absolute file offsets)
    return h.hexdigest()[:16]


if __name__ == "__main__":
    for path in sys.argv[1:]:
        print(digest(path))
