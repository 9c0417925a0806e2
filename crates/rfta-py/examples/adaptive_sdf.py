"""Reconstruct a mesh from an SDF you can evaluate, asking it only where the surface needs it.

The SDF here is plain numpy, batched the way a neural field's forward pass is: a ring with a
bead on it, the kind of SDF CAD and procedural modelling write. Any callable that takes an (n, 3) float64 array and returns n values
works the same way: a mesh's distance, a trained network (a PyTorch model:
``sdf=lambda p: model(torch.from_numpy(p).float()).detach().double().numpy().ravel()``; see
crates/rfta-py/README.md).

    python crates/rfta-py/examples/adaptive_sdf.py [OUT.obj]     (default adaptive_sdf.obj)
"""

import sys
import time

import numpy as np

import rfta


def sdf(p: np.ndarray) -> np.ndarray:
    """A ring with a bead on it: a torus (genus 1) and a ball around one side of its tube. The
    least of two exact SDFs is exact outside both and a lower bound inside, so every sample's
    sphere stays off the surface."""
    q = np.stack([np.hypot(p[:, 0], p[:, 1]) - 0.55, p[:, 2]], axis=1)
    torus = np.linalg.norm(q, axis=1) - 0.15
    bead = np.linalg.norm(p - [0.55, 0.0, 0.0], axis=1) - 0.3
    return np.minimum(torus, bead)


def main() -> None:
    out = sys.argv[1] if len(sys.argv) > 1 else "adaptive_sdf.obj"
    calls = []

    def counted(points: np.ndarray) -> np.ndarray:
        calls.append(len(points))
        return sdf(points)

    start = time.perf_counter()
    mesh = rfta.reconstruct(sdf=counted, bounds=(-1.0, 1.0), budget=10_000)
    seconds = time.perf_counter() - start
    a = mesh.adaptive
    assert sum(calls) == a["evaluations"] <= 10_000, (sum(calls), a["evaluations"])
    print(
        f"{len(mesh.vertices)} vertices, {len(mesh.faces)} faces from {a['evaluations']} "
        f"evaluations in {len(calls)} batches and {len(a['passes'])} passes; "
        f"{a['rfta_seconds']:.2f} s in rfta, {a['oracle_seconds']:.3f} s in the SDF "
        f"({seconds:.2f} s in all)"
    )
    err = np.abs(sdf(mesh.vertices))
    r = mesh.report
    print(f"|SDF| at the vertices: mean {err.mean():.5f}, max {err.max():.5f}")
    print(f"{r['components']} component(s), watertight {r['watertight']}")
    with open(out, "w") as f:
        f.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in mesh.vertices)
        f.writelines(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in mesh.faces)
    print(f"wrote {out}")
    assert r["watertight"] and r["components"] == 1 and err.mean() < 0.002, (r, err.mean())


if __name__ == "__main__":
    main()
