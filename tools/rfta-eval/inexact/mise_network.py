#!/usr/bin/env python3
"""MISE (Occupancy Networks' multiresolution isosurface extraction) on one of the inexact
evaluation's networks, as neural-field code runs it: a 16^3 grid, every cell whose corners change
sign split, to 128^3, then scikit-image's marching cubes on the value grid. Prints one JSON line:
evaluations, seconds outside the oracle, seconds in it.

    python mise_network.py NET.npy OUT.obj

Runs in a venv where `mise` imports (bash ../shared/peer-tests/mise/build.sh VENV); the network
(train.py's layout) is evaluated with numpy in float32, as train.py evaluates it.
"""
import json
import sys
import time

import numpy as np
from mise import MISE
from skimage.measure import marching_cubes

WIDTHS = [3, 128, 128, 128, 128, 1]
BETA = 10.0


def load(path):
    flat = np.load(path).astype(np.float32)
    layers, at = [], 0
    for n_in, n_out in zip(WIDTHS[:-1], WIDTHS[1:]):
        W = flat[at : at + n_in * n_out].reshape(n_in, n_out)
        at += n_in * n_out
        layers.append((W, flat[at : at + n_out]))
        at += n_out
    return layers


def values(layers, p):
    h = p.astype(np.float32)
    for k, (W, b) in enumerate(layers):
        h = h @ W + b
        if k < len(layers) - 1:
            h = np.logaddexp(0.0, BETA * h) / BETA
    return h[:, 0].astype(np.float64)


def main():
    net, out = sys.argv[1], sys.argv[2]
    layers = load(net)
    m = MISE(16, 3, 0.0)
    n, t_oracle, t0 = 0, 0.0, time.perf_counter()
    p = m.query()
    while len(p):
        X = -1.0 + 2.0 * p / m.resolution
        t1 = time.perf_counter()
        s = values(layers, X)
        t_oracle += time.perf_counter() - t1
        m.update(p, -s)
        n += len(p)
        p = m.query()
    G = -m.to_dense()
    h = 2.0 / m.resolution
    V, F, _, _ = marching_cubes(G, 0.0, spacing=(h, h, h))
    V -= 1.0
    with open(out, "w") as f:
        f.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in V)
        f.writelines(f"f {i + 1} {j + 1} {k + 1}\n" for i, j, k in F)
    print(json.dumps(dict(evaluations=int(n), seconds_outside_oracle=round(time.perf_counter() - t0 - t_oracle, 3),
                          seconds_oracle=round(t_oracle, 3), faces=int(len(F)), out=out)))


if __name__ == "__main__":
    main()
