#!/usr/bin/env python3
"""Writes the OpenVDB test files of rfta-io's reader with OpenVDB itself, and beside each level
set the dense grid OpenVDB makes of it (the "twin" the reader must reproduce).

Run with the system Python of Debian's python3-openvdb (OpenVDB 10.0.1):

    /usr/bin/python3 crates/rfta-io/tests/data/vdb/make.py

For each level set NAME.vdb: NAME.npy holds every voxel of the box of its active voxels and one
voxel more on every side (rfta's margin, which closes the band with inactive voxels), as
OpenVDB's copyToArray fills it (inactive voxels at plus or minus the background), as float32
with axis 0 along x; NAME.twin.json holds OpenVDB's world position of the box's first voxel
("origin"), the voxel size ("spacing") and the background (the clamp). Python cannot choose the
codec: codecs.cpp beside this script writes box.vdb again zipped, with no codec and as a double
grid (see its header for the build line).
"""
import json
import os

import numpy as np
import pyopenvdb as vdb

HERE = os.path.dirname(os.path.abspath(__file__))


def box_mesh(lo, hi):
    """The 8 corners and 12 triangles of an axis-aligned box, outward facing."""
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = np.array(
        [[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
         [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]],
        dtype=np.float32,
    )
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (2, 3, 7, 6), (1, 2, 6, 5), (0, 4, 7, 3)]
    tris = [t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))]
    return v, np.array(tris, dtype=np.int32)


def twin(grid, name):
    """Writes NAME.npy and NAME.json: the grid dense over its active box, by OpenVDB."""
    lo, hi = grid.evalActiveVoxelBoundingBox()
    lo = tuple(c - 1 for c in lo)
    hi = tuple(c + 1 for c in hi)
    dims = [hi[a] - lo[a] + 1 for a in range(3)]
    dense = np.zeros(dims, dtype=np.float32)
    grid.copyToArray(dense, ijk=lo)
    np.save(os.path.join(HERE, name + ".npy"), dense)
    side = {
        "origin": list(grid.transform.indexToWorld(lo)),
        "spacing": list(grid.transform.voxelSize()),
        "background": grid.background,
    }
    with open(os.path.join(HERE, name + ".twin.json"), "w") as f:
        json.dump(side, f, indent=1)


def main():
    # A box with three different extents, off the origin, on a grid whose voxel (0, 0, 0) is not
    # at the world origin: a swapped axis or a lost translation shows.
    xform = vdb.createLinearTransform(0.05)
    xform.translate((0.013, -0.021, 0.007))
    v, f = box_mesh((-0.3, -0.3, 0.05), (0.5, 0.2, 0.5))
    box = vdb.FloatGrid.createLevelSetFromPolygons(v, triangles=f, transform=xform, halfWidth=3.0)
    box.name = "box"
    vdb.write(os.path.join(HERE, "box.vdb"), grids=[box])
    twin(box, "box")

    half = box.deepCopy()
    half.saveFloatAsHalf = True
    vdb.write(os.path.join(HERE, "box-half.vdb"), grids=[half])

    # Three grids: a fog volume and a mask first, the level set third.
    fog = vdb.FloatGrid()
    fog.name = "density"
    fog.gridClass = vdb.GridClass.FOG_VOLUME
    fog.fill((0, 0, 0), (9, 9, 9), 0.5)
    mask = vdb.BoolGrid()
    mask.name = "mask"
    mask.fill((0, 0, 0), (3, 3, 3), True)
    ball = vdb.createLevelSetSphere(radius=0.4, center=(0.1, -0.2, 0.3), voxelSize=0.04, halfWidth=3.0)
    ball.name = "ball"
    vdb.write(os.path.join(HERE, "three.vdb"), grids=[fog, mask, ball])
    twin(ball, "ball")


if __name__ == "__main__":
    main()
