"""OpenVDB's side of `cargo xtask eval vdb`, run with the system Python of Debian's
python3-openvdb. For each (shape, voxel size) it is given, two narrow-band level sets (half width
3 voxels), each written as a .vdb with OpenVDB's own mesh of it (volumeToMesh through
`convertToPolygons`, isovalue 0, adaptivity 0: what Houdini and Blender users get; quads split
into triangles) as an .obj:

- "mesh": OpenVDB's mesh-to-volume conversion of the ground truth mesh (how a mesh becomes a
  level set in those tools);
- "exact": the exact signed distance (computed by the caller on the voxels, `sdf`, from index
  `lo`), clamped at the band and made a level set by OpenVDB: voxels at the background outside
  are not stored, voxels at or below its negative inside are inactive.

One JSON line per level set on stdout with the seconds OpenVDB's calls took.

Usage: openvdb.py JOBS.json  (a list of {"name", "gt", "voxel", "sdf", "lo", "out"}: writes
OUT-mesh.vdb, OUT-mesh-volumetomesh.obj, OUT-exact.vdb, OUT-exact-volumetomesh.obj)
"""
import json
import sys
import time

import numpy as np
import pyopenvdb as vdb


def read_obj(path):
    v, f = [], []
    with open(path) as fh:
        for line in fh:
            t = line.split()
            if not t:
                continue
            if t[0] == "v":
                v.append([float(x) for x in t[1:4]])
            elif t[0] == "f":
                idx = [int(x.split("/")[0]) - 1 for x in t[1:]]
                for k in range(1, len(idx) - 1):
                    f.append([idx[0], idx[k], idx[k + 1]])
    return np.array(v, dtype=np.float32), np.array(f, dtype=np.int32)


def write_obj(path, points, tris, quads):
    with open(path, "w") as fh:
        for p in points:
            fh.write("v %.9g %.9g %.9g\n" % (p[0], p[1], p[2]))
        for t in tris:
            fh.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))
        for q in quads:
            fh.write("f %d %d %d\n" % (q[0] + 1, q[1] + 1, q[2] + 1))
            fh.write("f %d %d %d\n" % (q[0] + 1, q[2] + 1, q[3] + 1))


def exact_level_set(job, xform):
    """The exact SDF as a level set: clamped to the band, outside beyond it left to the background,
    inside beyond it inactive at minus the background (what signedFloodFill leaves)."""
    background = 3.0 * job["voxel"]
    dense = np.clip(np.load(job["sdf"]).astype(np.float32), -background, background)
    grid = vdb.FloatGrid(background)
    grid.transform = xform
    grid.copyFromArray(dense, ijk=tuple(job["lo"]), tolerance=0.0)
    for item in grid.iterOnValues():
        if item.value <= -background:
            item.active = False
    grid.gridClass = vdb.GridClass.LEVEL_SET
    return grid


def mesh_and_report(job, grid, source, seconds):
    grid.name = job["name"]
    vdb.write(job["out"] + "-" + source + ".vdb", grids=[grid])
    t = time.perf_counter()
    points, tris, quads = grid.convertToPolygons(isovalue=0.0, adaptivity=0.0)
    to_mesh = time.perf_counter() - t
    write_obj(job["out"] + "-" + source + "-volumetomesh.obj", points, tris, quads)
    print(json.dumps({
        "name": job["name"],
        "voxel": job["voxel"],
        "source": source,
        "active": grid.activeVoxelCount(),
        "to_volume": seconds,
        "to_mesh": to_mesh,
    }), flush=True)


def main():
    with open(sys.argv[1]) as fh:
        jobs = json.load(fh)
    for job in jobs:
        v, f = read_obj(job["gt"])
        xform = vdb.createLinearTransform(job["voxel"])
        t = time.perf_counter()
        grid = vdb.FloatGrid.createLevelSetFromPolygons(v, triangles=f, transform=xform, halfWidth=3.0)
        mesh_and_report(job, grid, "mesh", time.perf_counter() - t)
        t = time.perf_counter()
        grid = exact_level_set(job, xform)
        mesh_and_report(job, grid, "exact", time.perf_counter() - t)


if __name__ == "__main__":
    main()
