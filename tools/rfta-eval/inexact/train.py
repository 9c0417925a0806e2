"""The inexact-fields evaluation's neural SDFs: one small MLP per dev shape, fitted DeepSDF-style.

    python tools/rfta-eval/inexact/train.py [--data ../shared/data] [--steps 4000] [NAME ...]

Each network is 3 -> 128 -> 128 -> 128 -> 128 -> 1 with softplus (beta 10) between layers, fitted
with Adam (learning rate 2e-3, halved every third of the steps, batches of 2048) to the L1 loss
against the exact signed distance clamped at +-0.1 (DeepSDF's clamp), on 200,000 points: a quarter
near the surface jittered by 0.01, a quarter jittered by 0.05, half uniform in [-1, 1]^3 (DeepSDF's
sampling). Like most trained SDFs its values are not distances: flat away from the surface (the
clamp), off by a few percent to tens of percent near it. The seed is the shape's position in the
sorted list of dev shapes.

Writes `NAME.npy` beside this script: float32, every layer's weights (row-major, inputs by outputs)
then its biases, layer after layer, the layout `cargo xtask eval inexact` reads. Trained once; the
evaluation never trains (numpy only, about two minutes a shape on two cores).
"""

import argparse
import os

import numpy as np

import rfta

WIDTHS = [128, 128, 128, 128]
BETA = 10.0
CLAMP = 0.1


def read_obj(path):
    V, F = [], []
    with open(path, encoding="utf-8") as f:
        for line in f:
            parts = line.split()
            if parts and parts[0] == "v":
                V.append([float(x) for x in parts[1:4]])
            elif parts and parts[0] == "f":
                F.append([int(x.split("/")[0]) - 1 for x in parts[1:4]])
    return np.array(V), np.array(F)


def on_surface(V, F, n, rng):
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    t = rng.choice(len(F), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    return a[t] + u[:, None] * (b[t] - a[t]) + v[:, None] * (c[t] - a[t])


def softplus(x):
    return np.logaddexp(0.0, BETA * x) / BETA


def softplus_slope(x):
    return 0.5 * (1.0 + np.tanh(0.5 * BETA * x))


def fit(X, y, steps, rng, batch=2048, lr=2e-3):
    sizes = list(zip([3] + WIDTHS, WIDTHS + [1]))
    P = []
    for n_in, n_out in sizes:
        P += [rng.normal(scale=np.sqrt(2.0 / n_in), size=(n_in, n_out)).astype(np.float32),
              np.zeros(n_out, np.float32)]
    m = [np.zeros_like(p) for p in P]
    v = [np.zeros_like(p) for p in P]
    layers = len(sizes)
    for step in range(1, steps + 1):
        i = rng.integers(0, len(X), size=batch)
        x, t = X[i], np.clip(y[i], -CLAMP, CLAMP)
        zs, hs = [], [x]
        for k in range(layers):
            z = hs[-1] @ P[2 * k] + P[2 * k + 1]
            zs.append(z)
            hs.append(softplus(z) if k < layers - 1 else z)
        g = (np.sign(hs[-1][:, 0] - t) / batch)[:, None].astype(np.float32)
        grads = [None] * len(P)
        for k in reversed(range(layers)):
            if k < layers - 1:
                g = g * softplus_slope(zs[k])
            grads[2 * k], grads[2 * k + 1] = hs[k].T @ g, g.sum(0)
            g = g @ P[2 * k].T
        rate = lr * 0.5 ** (3 * step // steps)
        for k in range(len(P)):
            m[k] = 0.9 * m[k] + 0.1 * grads[k]
            v[k] = 0.999 * v[k] + 0.001 * grads[k] ** 2
            P[k] -= rate * (m[k] / (1 - 0.9**step)) / (np.sqrt(v[k] / (1 - 0.999**step)) + 1e-8)
    return P


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=os.path.join(here, "../../../../shared/data"))
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("names", nargs="*")
    a = ap.parse_args()
    shapes = sorted(os.listdir(os.path.join(a.data, "inputs")))
    for seed, name in enumerate(shapes):
        if a.names and name not in a.names:
            continue
        rng = np.random.default_rng(seed)
        V, F = read_obj(os.path.join(a.data, "inputs", name, "gt.obj"))
        n = 200_000
        near = [on_surface(V, F, n // 4, rng) + rng.normal(scale=s, size=(n // 4, 3)) for s in (0.01, 0.05)]
        X = np.concatenate(near + [rng.uniform(-1.0, 1.0, size=(n // 2, 3))])
        y = rfta.signed_distance(X, V, F)
        P = fit(X.astype(np.float32), y.astype(np.float32), a.steps, rng)
        np.save(os.path.join(here, f"{name}.npy"), np.concatenate([p.ravel() for p in P]).astype(np.float32))
        print(name, "done", flush=True)


if __name__ == "__main__":
    main()
