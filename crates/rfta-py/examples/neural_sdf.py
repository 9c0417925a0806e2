"""A neural SDF meshed three ways: rfta asking the network where the surface needs it, marching
cubes on the network's 129^3 grid, and MISE (Occupancy Networks' extractor) when it is installed.

A small MLP (3 -> 48 -> 48 -> 1, softplus) is fitted DeepSDF-style to a dev shape's exact signed
distance (L1 to the distance clamped at 0.1, near-surface and uniform samples), on the CPU, with PyTorch
when it imports and ``--numpy`` is not given, else with its numpy twin (the same network, the same
training, written out with Adam). Each mesh is scored against the dev mesh with the evaluation's
Chamfer (``sqrt(mean d1^2) + sqrt(mean d2^2)``, area-weighted samples each way).

    python crates/rfta-py/examples/neural_sdf.py [--numpy] [--mesh gt.obj] [--steps 3000]
"""

import argparse
import os
import time

import numpy as np

import rfta

HIDDEN = 48


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


def surface_samples(V, F, n, rng):
    """n area-weighted points on the mesh (V, F)."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    t = rng.choice(len(F), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    return a[t] + u[:, None] * (b[t] - a[t]) + v[:, None] * (c[t] - a[t])


def chamfer(A, B, rng, n=50_000):
    """The evaluation's Chamfer distance between meshes A and B, each (V, F)."""
    one = lambda X, Y: np.sqrt(np.mean(rfta.signed_distance(surface_samples(*X, n, rng), *Y) ** 2))
    return one(A, B) + one(B, A)


def training_set(V, F, rng, n=40_000):
    near = surface_samples(V, F, n // 2, rng) + rng.normal(scale=0.02, size=(n // 2, 3))
    uniform = rng.uniform(-1.0, 1.0, size=(n - n // 2, 3))
    X = np.concatenate([near, uniform])
    return X, rfta.signed_distance(X, V, F)


BETA = 10.0


def softplus(x):
    """PyTorch's Softplus(beta=BETA): sharp enough for a shape's details."""
    return np.logaddexp(0.0, BETA * x) / BETA


def sigmoid(x):
    """softplus' derivative."""
    return 0.5 * (1.0 + np.tanh(0.5 * BETA * x))


def fit_numpy(X, y, steps, rng, batch=1024, lr=1e-2):
    """The numpy twin: the MLP, its gradients by hand, Adam."""
    sizes = [(3, HIDDEN), (HIDDEN, HIDDEN), (HIDDEN, 1)]
    params = []
    for n_in, n_out in sizes:
        params += [rng.normal(scale=np.sqrt(2.0 / n_in), size=(n_in, n_out)), np.zeros(n_out)]
    m = [np.zeros_like(p) for p in params]
    v = [np.zeros_like(p) for p in params]
    for step in range(1, steps + 1):
        i = rng.integers(0, len(X), size=batch)
        x, t = X[i], np.clip(y[i], -0.1, 0.1)
        z1 = x @ params[0] + params[1]
        h1 = softplus(z1)
        z2 = h1 @ params[2] + params[3]
        h2 = softplus(z2)
        out = (h2 @ params[4] + params[5])[:, 0]
        g = (np.sign(out - t) / batch)[:, None]
        grads = [None] * 6
        grads[4], grads[5] = h2.T @ g, g.sum(0)
        d2 = (g @ params[4].T) * sigmoid(z2)
        grads[2], grads[3] = h1.T @ d2, d2.sum(0)
        d1 = (d2 @ params[2].T) * sigmoid(z1)
        grads[0], grads[1] = x.T @ d1, d1.sum(0)
        for k, (p, gk) in enumerate(zip(params, grads)):
            m[k] = 0.9 * m[k] + 0.1 * gk
            v[k] = 0.999 * v[k] + 0.001 * gk * gk
            p -= lr * (m[k] / (1 - 0.9**step)) / (np.sqrt(v[k] / (1 - 0.999**step)) + 1e-8)

    def model(p):
        h = softplus(p @ params[0] + params[1])
        h = softplus(h @ params[2] + params[3])
        return (h @ params[4] + params[5])[:, 0]

    return model


def fit_torch(X, y, steps, rng, batch=1024, lr=1e-2):
    import torch

    torch.manual_seed(int(rng.integers(1 << 31)))
    net = torch.nn.Sequential(
        torch.nn.Linear(3, HIDDEN), torch.nn.Softplus(beta=BETA),
        torch.nn.Linear(HIDDEN, HIDDEN), torch.nn.Softplus(beta=BETA),
        torch.nn.Linear(HIDDEN, 1),
    ).double()
    opt = torch.optim.Adam(net.parameters(), lr=lr)
    Xt, yt = torch.from_numpy(X), torch.from_numpy(y)
    for _ in range(steps):
        i = torch.from_numpy(rng.integers(0, len(X), size=batch))
        out = net(Xt[i])[:, 0]
        loss = (out - yt[i].clamp(-0.1, 0.1)).abs().mean()
        opt.zero_grad()
        loss.backward()
        opt.step()
    # The network answers with a tensor; rfta brings it to the host itself.
    return lambda p: net(torch.from_numpy(p))[:, 0]


def on_grid(model, n=128):
    g = np.linspace(-1.0, 1.0, n + 1)
    P = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    S = np.concatenate([np.asarray(host(model(P[k : k + 65536]))) for k in range(0, len(P), 65536)])
    return S.reshape(n + 1, n + 1, n + 1)


def host(values):
    return values.detach().numpy() if hasattr(values, "detach") else values


def mise(model):
    """MISE to 128^3 as Occupancy Networks runs it, when its module is installed."""
    try:
        from mise import MISE
    except ImportError:
        return None
    m, n = MISE(16, 3, 0.0), 0
    p = m.query()
    while len(p):
        X = -1.0 + 2.0 * p / m.resolution
        m.update(p, -np.asarray(host(model(X)), dtype=np.float64))
        n += len(p)
        p = m.query()
    return rfta.marching_cubes(-m.to_dense(), bounds=(-1.0, 1.0)), n


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--numpy", action="store_true", help="the numpy twin even when torch imports")
    default = os.path.join(
        os.environ.get("RFTA_DATA_DIR", os.path.join(os.path.dirname(__file__), "../../../../shared/data")),
        "inputs/bunny/gt.obj",
    )
    ap.add_argument("--mesh", default=default)
    ap.add_argument("--steps", type=int, default=3000)
    a = ap.parse_args()
    rng = np.random.default_rng(7)
    V, F = read_obj(a.mesh)
    X, y = training_set(V, F, rng)
    use_torch = not a.numpy
    if use_torch:
        try:
            import torch  # noqa: F401
        except ImportError:
            use_torch = False
    t = time.perf_counter()
    model = (fit_torch if use_torch else fit_numpy)(X, y, a.steps, rng)
    print(f"trained with {'PyTorch' if use_torch else 'the numpy twin'} in {time.perf_counter() - t:.1f} s")
    gt = (V, F)
    asked = []

    def counted(p):
        asked.append(len(p))
        return model(p)

    t = time.perf_counter()
    r = rfta.reconstruct(sdf=counted, bounds=(-1.0, 1.0), budget=30_000)
    seconds = time.perf_counter() - t
    print(
        f"rfta adaptive: {sum(asked)} evaluations, {seconds:.1f} s, "
        f"Chamfer {chamfer((r.vertices, r.faces), gt, rng):.5f}, "
        f"genus {r.report['genus']} in {r.report['components']} component(s)"
    )
    t = time.perf_counter()
    Vm, Fm = rfta.marching_cubes(on_grid(model), bounds=(-1.0, 1.0))
    print(
        f"marching cubes 129^3: {129**3} evaluations, {time.perf_counter() - t:.1f} s, "
        f"Chamfer {chamfer((Vm, Fm), gt, rng):.5f}"
    )
    t = time.perf_counter()
    found = mise(model)
    if found is None:
        print("MISE: SKIPPED (its module is not installed: bash ../shared/peer-tests/mise/build.sh VENV)")
    else:
        (Vi, Fi), n = found
        print(
            f"MISE to 128^3: {n} evaluations, {time.perf_counter() - t:.1f} s, "
            f"Chamfer {chamfer((Vi, Fi), gt, rng):.5f}"
        )


if __name__ == "__main__":
    main()
