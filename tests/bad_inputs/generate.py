#!/usr/bin/env python3
"""Writes the bad-input corpus next to this script (Python 3 standard library only).

Every file is small and deterministic; README.md says what each one is and what rfta does with
it. The corpus is committed, so this script only needs to run again when a case is added:

    python3 tests/bad_inputs/generate.py

Two files are cut from outputs of rfta itself (`truncated.exr` from `rfta sample --shape sphere
--res 3 -o s.exr`, the first 300 bytes); they are kept as they are.
"""

import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
N = 12  # cells per axis: 13^3 samples over [-1, 1]^3, spacing 1/6


def path(name):
    return os.path.join(HERE, name)


def write(name, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path(name), mode) as f:
        f.write(data)


def png(width, height, values, bits=16):
    """A grayscale PNG (no filtering), `values` row by row from the top."""
    import zlib

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    fmt = ">H" if bits == 16 else ">B"
    rows = b"".join(
        b"\0" + b"".join(struct.pack(fmt, values[r * width + c]) for c in range(width))
        for r in range(height)
    )
    header = struct.pack(">IIBBBBB", width, height, bits, 0, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(rows))
        + chunk(b"IEND", b"")
    )


def npy(shape, values, descr="<f4", fortran=False):
    """A version 1.0 .npy file; `values` in C order (transposed here for Fortran order)."""
    if fortran and len(shape) > 1:
        strides_c = [1] * len(shape)
        for a in range(len(shape) - 2, -1, -1):
            strides_c[a] = strides_c[a + 1] * shape[a + 1]
        out = []
        total = 1
        for s in shape:
            total *= s
        idx = [0] * len(shape)
        for _ in range(total):
            out.append(values[sum(i * s for i, s in zip(idx, strides_c))])
            for a in range(len(shape)):  # first axis fastest
                idx[a] += 1
                if idx[a] < shape[a]:
                    break
                idx[a] = 0
        values = out
    shape_text = "(" + ", ".join(str(s) for s in shape) + ("," if len(shape) == 1 else "") + ")"
    header = "{'descr': '%s', 'fortran_order': %s, 'shape': %s, }" % (
        descr,
        "True" if fortran else "False",
        shape_text,
    )
    pad = 64 - (10 + len(header) + 1) % 64
    header = header + " " * pad + "\n"
    fmt = {"<f8": "<d", ">f8": ">d", "<f4": "<f", "<i4": "<i"}[descr]
    body = b"".join(struct.pack(fmt, v) for v in values)
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode() + body


def grid_positions(n=N):
    for i in range(n + 1):
        for j in range(n + 1):
            for k in range(n + 1):
                yield ((2 * i - n) / n, (2 * j - n) / n, (2 * k - n) / n)


def sphere(p, r=0.5):
    return math.sqrt(p[0] ** 2 + p[1] ** 2 + p[2] ** 2) - r


class Lcg:
    """A fixed generator (Numerical Recipes' LCG) so the corpus never changes."""

    def __init__(self, seed):
        self.s = seed

    def uniform(self):
        self.s = (1664525 * self.s + 1013904223) % 2**32
        return self.s / 2**32


def main():
    dims = (N + 1,) * 3
    sph = [sphere(p) for p in grid_positions()]

    # Values that are not numbers.
    nan = list(sph)
    nan[100] = float("nan")
    write("nan.npy", npy(dims, nan))
    inf = list(sph)
    inf[7] = float("-inf")
    write("inf.npy", npy(dims, inf))

    # .npy layout: wrong dtype, wrong shape, and the two other legal layouts of the same grid.
    write("int32.npy", npy(dims, [int(v * 1000) for v in sph], descr="<i4"))
    write("shape_2d.npy", npy((13, 169), sph))
    write("shape_4d.npy", npy((13, 13, 13, 1), sph))

    # 2D: a disc's SDF with a NaN, a 1-pixel image, an 8-bit image, an image without its value
    # range, a CSV whose rows change width.
    disc = [math.hypot(-1 + i / 4, -1 + j / 4) - 0.5 for i in range(9) for j in range(9)]
    disc[10] = float("nan")
    write("nan_2d.npy", npy((9, 9), disc, descr="<f8"))
    write("pixel_1.png", png(1, 1, [30000]))
    write("pixel_1.json", json.dumps({"values": [-1, 1]}))
    write("gray_8bit.png", png(4, 4, list(range(16)), bits=8))
    write("gray_8bit.json", json.dumps({"values": [-1, 1]}))
    write("no_range.png", png(4, 4, [1000 * k for k in range(16)]))
    write("ragged_2d.csv", "x,y,s\n0,0,-0.5\n1,0,0.5\n0,1,0.5,7\n")
    write("sphere.npy", npy(dims, sph, descr="<f8"))
    write("sphere_fortran.npy", npy(dims, sph, descr="<f8", fortran=True))
    write("sphere_bigendian.npy", npy(dims, sph, descr=">f8"))

    # Truncated and garbage files of every reader.
    whole = npy(dims, sph)
    write("truncated.npy", whole[: len(whole) - 1000])
    write("header_only.npy", whole[:128])
    rng = Lcg(1)
    garbage = bytes(int(rng.uniform() * 256) for _ in range(4096))
    for ext in ["npy", "exr", "ply", "obj", "off", "stl", "glb", "csv"]:
        write("garbage." + ext, garbage)
        write("empty." + ext, b"")
    write(
        "truncated.ply",
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
        "property float z\nproperty float sdf\nend_header\n0 0 0 -0.5\n1 0 0 0.5\n0 1",
    )
    bin_ply = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty double x\n"
        b"property double y\nproperty double z\nproperty double sdf\nend_header\n"
        + b"".join(struct.pack("<4d", i, 0, 0, i - 50) for i in range(60))
    )
    write("truncated_binary.ply", bin_ply)
    write("truncated.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\nv 0 0")
    write("truncated.off", "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1")
    tri = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
    write("truncated.stl", b"\0" * 80 + struct.pack("<I", 12) + tri * 3)
    gltf = json.dumps(
        {
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": 1000}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"}
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
            "nodes": [{"mesh": 0}],
            "scenes": [{"nodes": [0]}],
        }
    ).encode()
    gltf += b" " * ((4 - len(gltf) % 4) % 4)
    glb = (
        b"glTF"
        + struct.pack("<II", 2, 12 + 8 + len(gltf) + 8 + 1000)
        + struct.pack("<I", len(gltf))
        + b"JSON"
        + gltf
        + struct.pack("<I", 1000)
        + b"BIN\0"
        + b"\0" * 40
    )
    write("truncated.glb", glb)
    write("short_row.csv", "x,y,z,s\n0,0,0,-0.5\n1,0,0,0.5\n0,1,0\n")
    write("not_a_number.csv", "x,y,z,s\n0,0,0,-0.5\n1,0,0,zero\n")

    # Sidecars with unusable bounds.
    write("inverted_bounds.npy", npy(dims, sph))
    write("inverted_bounds.json", json.dumps({"min": [1, 1, 1], "max": [-1, -1, -1]}))
    write("zero_bounds.npy", npy(dims, sph))
    write("zero_bounds.json", json.dumps({"min": [0, 0, 0], "max": [0, 1, 1]}))
    write("bad_sidecar.npy", npy(dims, sph))
    write("bad_sidecar.json", '{"min": [0, 0, 0], "max": [1, 1]')

    # Tiny grids.
    write("grid_1.npy", npy((1, 1, 1), [-0.5]))
    write("grid_2.npy", npy((2, 1, 1), [-0.5, 0.5]))
    write("grid_2x2x2.npy", npy((2, 2, 2), [-0.2, 0.9, 0.9, 1.5, 0.9, 1.5, 1.5, 2.0]))

    # No surface, or hardly one.
    write("all_positive.npy", npy(dims, [abs(v) + 0.1 for v in sph]))
    write("all_negative.npy", npy(dims, [-abs(v) - 0.1 for v in sph]))
    centre = (N // 2) * (N + 1) ** 2 + (N // 2) * (N + 1) + N // 2
    single = [2.0 / N * 0.9] * len(sph)
    single[centre] = -0.05
    write("single_negative.npy", npy(dims, single))
    zeros = list(sph)  # 30 grid points, (0.5, 0, 0) and (1/3, 1/3, 1/6) up to symmetry, give 0
    assert sum(1 for v in zeros if v == 0.0) == 30
    write("zeros.npy", npy(dims, zeros))
    write("all_zero.npy", npy(dims, [0.0] * len(sph)))

    # Values that are not distances.
    rng = Lcg(2)
    write("random.npy", npy(dims, [2 * rng.uniform() - 1 for _ in sph]))
    write("occupancy.npy", npy(dims, [-1.0 if v < 0 else 1.0 for v in sph]))
    rng = Lcg(3)
    write("noisy.npy", npy(dims, [v * (1 + 0.05 * (2 * rng.uniform() - 1)) for v in sph]))
    band = 2 * 2.0 / N
    write("clamped.npy", npy(dims, [max(-band, min(band, v)) for v in sph]))
    huge = list(sph)
    huge[0] = 1e30
    write("huge.npy", npy(dims, huge))
    write("scaled.npy", npy(dims, [1.5 * v for v in sph]))

    # Scattered samples: the same position twice with different values.
    rows = ["x,y,z,s"]
    for i, p in enumerate(grid_positions(6)):
        rows.append("%.6f,%.6f,%.6f,%.6f" % (p[0], p[1], p[2], sphere(p)))
    rows.append("%.6f,%.6f,%.6f,%.6f" % (0.0, 0.0, 0.0, 0.25))
    write("coincident.csv", "\n".join(rows) + "\n")

    # A header claiming a 513^3 float32 grid (540 MB of data, 0.2 billion samples) with no data.
    write("oversized_513.npy", npy((513, 513, 513), [], descr="<f4"))


if __name__ == "__main__":
    main()
