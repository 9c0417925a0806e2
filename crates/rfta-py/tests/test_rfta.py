"""The rfta Python package: the drop-in signature, agreement with the CLI, the GIL, errors.

Run: pip install crates/rfta-py[test] && pytest crates/rfta-py/tests
(RFTA_BIN names the rfta binary for the CLI comparison; `cargo xtask ci` sets it.)
"""

import contextlib
import inspect
import json
import os
import signal
import subprocess
import threading
import time
import warnings

import numpy as np
import pytest

import rfta


def grid(n, lo=-1.0, hi=1.0):
    """The points of linspace(lo, hi, n + 1)^3 as numpy's meshgrid(indexing="ij") gives them."""
    g = np.linspace(lo, hi, n + 1)
    return np.stack(np.meshgrid(g, g, g, indexing="ij"), -1)


@contextlib.contextmanager
def interrupted_after(seconds):
    """Ctrl-C (SIGINT to this process) after `seconds`. A shell that starts the tests in the
    background ignores SIGINT, and Python then keeps it ignored: the handler that raises
    KeyboardInterrupt is installed for the block's length."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        yield
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)


def torus_sdf(p, R=0.5, r=0.2):
    q = np.sqrt(p[..., 0] ** 2 + p[..., 1] ** 2) - R
    return np.sqrt(q**2 + p[..., 2] ** 2) - r


def read_obj(path):
    V, F = [], []
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "v":
                V.append([float(x) for x in t[1:4]])
            elif t and t[0] == "f":
                F.append([int(x.split("/")[0]) - 1 for x in t[1:4]])
    return np.array(V), np.array(F)


# gpytoolbox 0.3.8's signature, argument for argument (names and defaults).
GPYTOOLBOX = [
    ("U", inspect.Parameter.empty),
    ("S", inspect.Parameter.empty),
    ("rng_seed", 3452),
    ("return_point_cloud", False),
    ("fine_tune_iters", 3),
    ("batch_size", 10000),
    ("num_rasterization_spheres", 0),
    ("screening_weight", 10.0),
    ("rasterization_resolution", None),
    ("max_points_per_sphere", 3),
    ("n_local_searches", None),
    ("local_search_iters", 20),
    ("local_search_t", 0.01),
    ("tol", 1e-4),
    ("clamp_value", np.inf),
    ("force_cpu", False),
    ("parallel", False),
    ("verbose", False),
]


def test_the_drop_in_has_gpytoolboxs_signature():
    params = inspect.signature(rfta.reach_for_the_arcs).parameters
    assert [(n, p.default) for n, p in params.items()] == GPYTOOLBOX


def test_the_drop_in_reconstructs_a_torus_from_gpytoolboxs_meshgrid():
    # gpytoolbox's docstring builds U with meshgrid's default "xy" indexing: y slowest.
    g = np.linspace(-1.0, 1.0, 21)
    gx, gy, gz = np.meshgrid(g, g, g)
    U = np.vstack((gx.flatten(), gy.flatten(), gz.flatten())).T
    S = torus_sdf(U)
    V, F = rfta.reach_for_the_arcs(U, S)
    assert V.dtype == np.float64 and V.shape[1] == 3
    assert F.dtype == np.int32 and F.shape[1] == 3 and F.max() < len(V)
    # Vertices on the torus: on average within 2% of the grid spacing (0.1; marching cubes on
    # the same grid: 1.0%), every one within half of it.
    err = np.abs(torus_sdf(V))
    assert err.mean() < 0.002 and err.max() < 0.05
    V2, F2, P, N = rfta.reach_for_the_arcs(U, S, return_point_cloud=True)
    assert np.array_equal(V, V2) and np.array_equal(F, F2)
    assert P.shape == N.shape and np.allclose(np.linalg.norm(N, axis=1), 1.0)
    # The points are recognised as a grid: the same mesh as the grid itself in the fast preset
    # (gpytoolbox's defaults), unsimplified as gpytoolbox's.
    S_ij = torus_sdf(grid(20))
    r = rfta.reconstruct(S_ij, bounds=(-1, 1), preset="fast", simplify=False)
    assert r.report["grid"]
    assert np.array_equal(r.vertices, V) and np.array_equal(r.faces, F)


def test_same_mesh_as_the_cli(tmp_path):
    exe = os.environ.get("RFTA_BIN")
    if not exe:
        pytest.skip("RFTA_BIN is not set (cargo xtask ci sets it)")
    S = torus_sdf(grid(16))
    np.save(tmp_path / "torus.npy", S)
    out = tmp_path / "torus.obj"
    report = tmp_path / "report.json"
    subprocess.run(
        [exe, "-q", "reconstruct", str(tmp_path / "torus.npy"), "-o", str(out),
         "--bounds=-1,1", "--seed", "7", "--rounds", "4", "--max-points-per-sphere", "2",
         "--report", str(report)],
        check=True,
    )
    V, F = read_obj(out)
    r = rfta.reconstruct(S, bounds=(-1, 1), seed=7, rounds=4, max_points_per_sphere=2)
    assert np.array_equal(r.vertices, V)
    assert np.array_equal(r.faces, F)
    # One definition of the report (rfta::Report's serde form): the same figures by the same
    # names, the CLI adding the mesh's size and its seconds, Python whether it was a grid.
    cli = json.loads(report.read_text())
    assert set(cli) - {"vertices", "faces", "seconds"} == set(r.report) - {"grid"}
    for key in ["samples", "components", "sign_errors", "entered", "cavities", "points_per_round"]:
        assert cli[key] == r.report[key], key
    assert cli["timings"].keys() == r.report["timings"].keys()


def test_a_wrong_setting_is_refused_by_name():
    S = torus_sdf(grid(8))
    with pytest.raises(ValueError, match="rounds"):
        rfta.reconstruct(S, bounds=(-1, 1), rounds=2.5)
    with pytest.raises(ValueError, match="clamp"):
        rfta.reconstruct(S, bounds=(-1, 1), clamp=float("inf"))


def test_a_known_genus_cuts_the_torus_and_the_report_says_so():
    S = torus_sdf(grid(20), R=0.6, r=0.2)
    plain = rfta.reconstruct(S, bounds=(-1, 1))
    assert plain.report["handles_cut"] == 0
    assert plain.report["thin_loops"] == []  # the tube is 4 spacings across
    cut = rfta.reconstruct(S, bounds=(-1, 1), genus=0)
    assert cut.report["handles_cut"] == 1
    assert cut.report["components_joined"] == 0
    # Euler characteristic 2: a sphere (V - E + F with E = 3F/2 on a closed mesh).
    assert len(cut.vertices) - len(cut.faces) // 2 == 2


def test_float32_and_non_contiguous_input():
    S = torus_sdf(grid(12))
    base = rfta.reconstruct(S, rounds=2, simplify=False)
    fortran = rfta.reconstruct(np.asfortranarray(S), rounds=2, simplify=False)
    assert np.array_equal(base.vertices, fortran.vertices)
    # Every other point of a finer grid: a strided view of the same samples.
    fine = torus_sdf(grid(24))[::2, ::2, ::2]
    assert not fine.flags["C_CONTIGUOUS"]
    strided = rfta.reconstruct(fine, rounds=2, simplify=False)
    assert np.array_equal(base.vertices, strided.vertices)
    # float32 values: a mesh as close to the torus (spacing 1/6: within 2.5% on average, half a
    # spacing at worst).
    single = rfta.reconstruct(S.astype(np.float32), rounds=2, simplify=False)
    err = np.abs(torus_sdf(single.vertices))
    assert err.mean() < 0.004 and err.max() < 0.08


def test_the_gil_is_released_while_it_works():
    S = torus_sdf(grid(28))
    counts = []
    stop = threading.Event()

    def count():
        n = 0
        while not stop.is_set():
            n += 1
            time.sleep(0.001)
        counts.append(n)

    t = threading.Thread(target=count)
    t.start()
    start = time.time()
    rfta.reconstruct(S, threads=1)
    took = time.time() - start
    stop.set()
    t.join()
    # The counter sleeps 1 ms a step: with the GIL held by the reconstruction it could not run.
    assert took > 0.2
    assert counts[0] > 0.2 * took / 0.001


def test_bad_input_is_a_value_error():
    U = grid(6).reshape(-1, 3)
    S = torus_sdf(U)
    nan = S.copy()
    nan[10] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        rfta.reach_for_the_arcs(U, nan)
    with pytest.raises(ValueError, match="shape"):
        rfta.reach_for_the_arcs(U[:, :2].T, S)
    with pytest.raises(ValueError, match="values"):
        rfta.reach_for_the_arcs(U, S[:-1])
    # Dropping z leaves 2D samples with several values at one position.
    with pytest.raises(ValueError, match="different values"):
        rfta.reach_for_the_arcs(U[:, :2], S)
    with pytest.raises(ValueError, match="3 dimension"):
        rfta.reconstruct(S)
    with pytest.raises(ValueError, match="bounds"):
        rfta.reconstruct(S.reshape(7, 7, 7), bounds=(1, -1))
    with pytest.raises(ValueError, match="preset"):
        rfta.reconstruct(S.reshape(7, 7, 7), preset="fastest")
    # Not a distance: random values are refused by the check, with the library's message.
    rng = np.random.default_rng(1)
    with pytest.raises(ValueError, match="distance"):
        rfta.reconstruct(rng.uniform(-1, 1, (9, 9, 9)))


def test_the_drop_in_reconstructs_2d_samples_as_closed_polylines():
    # gpytoolbox's 2D call: U (n, 2) from a meshgrid, here a disc of radius 0.5 on 33^2 points.
    g = np.linspace(-1.0, 1.0, 33)
    U = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
    S = np.linalg.norm(U - [0.1, 0.0], axis=1) - 0.5
    V, E, P, N = rfta.reach_for_the_arcs(U, S, return_point_cloud=True)
    assert V.shape[1] == 2 and E.shape[1] == 2 and E.dtype == np.int32
    assert np.abs(np.linalg.norm(V - [0.1, 0.0], axis=1) - 0.5).max() < 0.01
    # Closed: every vertex starts one edge and ends one; counter-clockwise (positive area).
    assert sorted(E[:, 0]) == sorted(E[:, 1])
    area = 0.5 * np.sum(V[E[:, 0], 0] * V[E[:, 1], 1] - V[E[:, 1], 0] * V[E[:, 0], 1])
    assert abs(area - np.pi * 0.25) < 0.01
    assert P.shape == N.shape and P.shape[1] == 2


def test_no_surface_is_its_own_value_error():
    with pytest.raises(rfta.NoSurfaceError, match="no surface"):
        rfta.reconstruct(np.full((6, 6, 6), 3.0))
    assert issubclass(rfta.NoSurfaceError, ValueError)


@pytest.mark.parametrize("d", [2, 3])
def test_the_drop_in_answers_no_surface_with_empty_arrays(d):
    # Every sample 5 from a surface that is nowhere: the circles or spheres cover the box.
    g = np.linspace(0.0, 1.0, 6)
    U = np.stack(np.meshgrid(*[g] * d), -1).reshape(-1, d)
    S = np.full(len(U), 5.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # quiet unless verbose
        V, F = rfta.reach_for_the_arcs(U, S)
    assert V.shape == (0, d) and V.dtype == np.float64
    assert F.shape == (0, d) and F.dtype == np.int32
    with pytest.warns(UserWarning, match="no surface"):
        V, F, P, N = rfta.reach_for_the_arcs(U, S, return_point_cloud=True, verbose=True)
    assert V.shape == F.shape == P.shape == N.shape == (0, d)
    assert P.dtype == N.dtype == np.float64


def unreferenced(V, F):
    used = np.zeros(len(V), bool)
    used[np.asarray(F).ravel()] = True
    return int((~used).sum())


def test_no_output_has_an_unreferenced_vertex():
    # 2D: a ring 0.24 wide on coarse grids, where the island rule removes small loops (it used
    # to leave their vertices behind: gpytoolbox's test of parallel runs measured them).
    for n in range(7, 16):
        g = np.linspace(-1.0, 1.0, n)
        U = np.stack(np.meshgrid(g, g), -1).reshape(-1, 2)
        S = np.abs(np.linalg.norm(U, axis=1) - 0.5) - 0.12
        for parallel in (False, True):
            V, E = rfta.reach_for_the_arcs(U, S, parallel=parallel)
            assert len(E) and unreferenced(V, E) == 0, (n, parallel)
    S = torus_sdf(grid(12))
    r = rfta.reconstruct(S)
    assert unreferenced(r.vertices, r.faces) == 0
    V, F = rfta.reach_for_the_arcs(grid(12).reshape(-1, 3), S.ravel())
    assert unreferenced(V, F) == 0
    assert unreferenced(*rfta.marching_cubes(S)) == 0
    assert unreferenced(*rfta.screened_poisson(r.points, r.normals)) == 0


def test_the_module_exports_only_its_api():
    public = {n for n in dir(rfta) if not n.startswith("_")}
    assert public == set(rfta.__all__) - {"__version__"}
    assert isinstance(rfta.__version__, str)
    assert rfta.reconstruct.__module__ == "rfta" and rfta.Reconstruction.__module__ == "rfta"


def test_progress_is_reported_and_an_exception_in_it_stops_the_run():
    seen = []
    rfta.reconstruct(torus_sdf(grid(10)), rounds=3, progress=lambda s, d, o: seen.append(s))
    assert seen[0] == "initial" and "round 3/3" in seen and seen[-1] == "final"

    class Stop(Exception):
        pass

    def stop_at_round_2(stage, done, of):
        if stage == "round 2/10":
            raise Stop()

    with pytest.raises(Stop):
        rfta.reconstruct(torus_sdf(grid(10)), progress=stop_at_round_2)


@pytest.mark.skipif(os.name != "posix", reason="SIGINT by os.kill")
def test_ctrl_c_stops_a_long_run():
    S = torus_sdf(grid(40))
    start = time.time()
    with interrupted_after(0.5), pytest.raises(KeyboardInterrupt):
        rfta.reconstruct(S, preset="paper", threads=1)
    # The paper preset at 41^3 takes far longer; the run stops at the next round.
    assert time.time() - start < 30


def test_the_other_functions():
    # Marching cubes and sampling of a sphere.
    S = np.linalg.norm(grid(20), axis=-1) - 0.5
    V, F = rfta.marching_cubes(S, bounds=(-1, 1))
    assert np.abs(np.linalg.norm(V, axis=1) - 0.5).max() < 0.01
    # The exact distance of that mesh, on a grid and at points, against the sphere's.
    D = rfta.sample_sdf(V, F, 10)
    assert D.shape == (11, 11, 11)
    exact = np.linalg.norm(grid(10), axis=-1) - 0.5
    assert np.abs(D - exact).max() < 0.01
    q = np.array([[0.0, 0.0, 0.0], [0.9, 0.0, 0.0], [0.0, 0.6, 0.0]])
    assert np.allclose(rfta.signed_distance(q, V, F), [-0.5, 0.4, 0.1], atol=0.01)
    # Screened Poisson of points on the sphere with their normals.
    rng = np.random.default_rng(3)
    N = rng.normal(size=(4000, 3))
    N /= np.linalg.norm(N, axis=1)[:, None]
    V, F = rfta.screened_poisson(0.5 * N, N, depth=6)
    assert np.abs(np.linalg.norm(V, axis=1) - 0.5).max() < 0.02
    with pytest.raises(ValueError, match="outside"):
        rfta.signed_distance(q, V, F + len(V))


def surface_samples(V, F, n, rng):
    """n points on the mesh, uniform by area."""
    a, b, c = V[F[:, 0]], V[F[:, 1]], V[F[:, 2]]
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    f = rng.choice(len(F), size=n, p=area / area.sum())
    u, v = rng.random(n), rng.random(n)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    return a[f] + u[:, None] * (b[f] - a[f]) + v[:, None] * (c[f] - a[f])


def torus_chamfer(V, F, rng):
    """Mean distance from the mesh to the torus plus from the torus to the mesh."""
    t, p = rng.random(20000) * 2 * np.pi, rng.random(20000) * 2 * np.pi
    ring = 0.5 + 0.2 * np.cos(p)
    on_torus = np.stack([ring * np.cos(t), ring * np.sin(t), 0.2 * np.sin(p)], -1)
    to_mesh = np.abs(rfta.signed_distance(on_torus, V, F)).mean()
    to_torus = np.abs(torus_sdf(surface_samples(V, F, 20000, rng))).mean()
    return to_mesh + to_torus


def test_side_by_side_with_gpytoolbox():
    gpy = pytest.importorskip("gpytoolbox")
    U = grid(12).reshape(-1, 3)
    S = torus_sdf(U)
    V, F = rfta.reach_for_the_arcs(U, S)
    Vg, Fg = gpy.reach_for_the_arcs(U, S)
    ours = torus_chamfer(V, F, np.random.default_rng(5))
    theirs = torus_chamfer(Vg, np.asarray(Fg), np.random.default_rng(5))
    assert ours <= theirs, (ours, theirs)


def test_a_reconstruction_writes_its_page(tmp_path):
    S = torus_sdf(grid(16))
    r = rfta.reconstruct(S, bounds=(-1, 1))
    page = r.to_html(tmp_path / "t.html", title="a torus")
    assert page.startswith("<!DOCTYPE html>") and "a torus" in page
    assert (tmp_path / "t.html").read_text(encoding="utf-8") == page
    # The report's figures and the markings are in it; nothing is fetched from a network.
    assert "sign_errors" in page and "loops around thin handles" in page
    assert "marching cubes (same samples)" in page
    assert 'src="http' not in page and 'href="http' not in page


VDB = os.path.join(os.path.dirname(__file__), "..", "..", "rfta-io", "tests", "data", "vdb")


def test_read_sdf_gives_an_openvdb_level_set_as_openvdb_makes_it_dense():
    # box.vdb and its dense twin were written by OpenVDB 10 (rfta-io/tests/data/vdb/make.py).
    s = rfta.read_sdf(os.path.join(VDB, "box.vdb"))
    twin = np.load(os.path.join(VDB, "box.npy"))
    with open(os.path.join(VDB, "box.twin.json")) as f:
        meta = json.load(f)
    assert isinstance(s, rfta.Samples) and s.points is None
    assert s.S.shape == twin.shape
    assert np.array_equal(s.S, twin.astype(np.float64))
    assert s.bounds[0] == tuple(meta["origin"])
    assert s.clamp == meta["background"]
    assert '"box"' in s.description
    r = rfta.reconstruct(s, preset="fast")
    assert r.report["clamp"] == meta["background"]
    assert r.report["components"] == 1 and r.report["watertight"]
    # The box make.py gave OpenVDB, within a voxel (0.05).
    assert np.allclose(r.vertices.min(0), [-0.3, -0.3, 0.05], atol=0.05)
    assert np.allclose(r.vertices.max(0), [0.5, 0.2, 0.5], atol=0.05)


def test_read_sdf_names_what_it_cannot_read():
    with pytest.raises(ValueError, match="fog volume, not a level set"):
        rfta.read_sdf(os.path.join(VDB, "three.vdb"), grid="density")
    with pytest.raises(ValueError, match='no grid named "nope"'):
        rfta.read_sdf(os.path.join(VDB, "three.vdb"), grid="nope")
    with pytest.raises(OSError):
        rfta.read_sdf(os.path.join(VDB, "missing.vdb"))
    s = rfta.read_sdf(os.path.join(VDB, "three.vdb"), grid="ball")
    assert s.S.ndim == 3 and s.clamp > 0


def test_initial_points_from_the_gradients_or_the_raster():
    S = torus_sdf(grid(12))
    assert rfta.reconstruct(S, preset="fast").report["raster_resolution"] == 0
    assert rfta.reconstruct(S, preset="fast", initial="raster").report["raster_resolution"] >= 64
    with pytest.raises(ValueError, match="initial"):
        rfta.reconstruct(S, preset="fast", initial="teapot")


def test_a_field_that_is_not_a_distance_is_read_as_a_level_set():
    # A torus' distance flattened at 0.1 (as a network trained on a clamp answers), its slope
    # near the surface off by up to 30%: the same zero set, values that fall short of it.
    def flat(p):
        return 0.1 * np.tanh(torus_sdf(p) / 0.1) * (1.0 + 0.3 * np.sin(3.0 * p[..., 0]))

    with pytest.warns(rfta.RftaWarning, match="not distances"):
        r = rfta.reconstruct(flat(grid(24)))
    assert r.report["read_as"] == "level-set" and r.report["reach"] < 0.5, r.report
    assert r.report["components"] == 1 and r.report["genus"] == 1
    # Its vertices on the torus within a tenth of a spacing (2 / 24).
    assert np.abs(torus_sdf(r.vertices)).max() < 0.1 * 2.0 / 24.0
    exact = rfta.reconstruct(torus_sdf(grid(16)), preset="fast").report
    assert exact["read_as"] == "distances" and exact["spheres_covered"] < 0.005, exact
    forced = rfta.reconstruct(torus_sdf(grid(16)), field="level-set")
    assert forced.report["read_as"] == "level-set"
    with pytest.raises(ValueError, match="field"):
        rfta.reconstruct(torus_sdf(grid(12)), field="occupancy")
    # As a function to ask: refined where its sign changes, within the budget.
    asked = []

    def counted(p):
        asked.append(len(p))
        return flat(p)

    r = rfta.reconstruct(sdf=counted, bounds=(-1, 1), budget=8000)
    assert sum(asked) <= 8000 and r.report["read_as"] == "level-set"
    assert r.report["components"] == 1 and r.report["genus"] == 1


def test_a_csg_bound_is_read_as_bounds():
    # A cube intersected with a ball and drilled by three cylinders, by min and max: a bound whose
    # spheres near the drills lie inside others. Read as bounds, one closed piece of genus 5 with
    # no sample on the wrong side.
    p = grid(24)
    cube = np.linalg.norm(np.maximum(np.abs(p) - 0.45, 0.0), axis=-1) + np.minimum(
        (np.abs(p) - 0.45).max(axis=-1), 0.0
    )
    body = np.maximum(cube, np.linalg.norm(p, axis=-1) - 0.6)
    drills = [np.linalg.norm(np.delete(p, a, axis=-1), axis=-1) - 0.2 for a in range(3)]
    S = np.maximum(body, -np.minimum(np.minimum(drills[0], drills[1]), drills[2]))
    with pytest.warns(rfta.RftaWarning, match="CSG"):
        r = rfta.reconstruct(S)
    assert r.report["read_as"] == "bounds" and r.report["spheres_covered"] > 0.005, r.report
    assert r.report["components"] == 1 and r.report["genus"] == 5
    assert r.report["sign_errors"] == 0 and r.report["moved_onto_zero_set"] > 0
    assert rfta.reconstruct(S, field="distance", rounds=1).report["read_as"] == "distances"


def test_a_callable_sdf_is_asked_within_the_budget():
    calls = []

    def sdf(p):
        assert p.dtype == np.float64 and p.ndim == 2 and p.shape[1] == 3
        calls.append(len(p))
        return list(torus_sdf(p))  # anything numpy.asarray takes

    out = rfta.reconstruct(sdf=sdf, budget=2000, rounds=2)
    a = out.adaptive
    assert sum(calls) == a["evaluations"] <= 2000
    assert len(a["passes"]) >= 2 and a["oracle_seconds"] >= 0 and a["rfta_seconds"] > 0
    assert out.report["watertight"] and out.report["components"] == 1
    # Within a hundredth of the torus on average (its tube is 0.4 across).
    assert np.abs(torus_sdf(out.vertices)).mean() < 0.01
    values, positions, grid_ = out.samples
    assert grid_ is None and len(values) == len(positions) <= 2000


def test_a_failing_callable_raises_its_own_error_or_names_the_batch():
    class ModelDown(Exception):
        pass

    def down(p):
        raise ModelDown("the model server is down")

    with pytest.raises(ModelDown, match="server is down"):
        rfta.reconstruct(sdf=down, budget=500)
    with pytest.raises(ValueError, match="batch 1.*NaN"):
        rfta.reconstruct(sdf=lambda p: np.full(len(p), np.nan), budget=500)
    with pytest.raises(ValueError, match="batch 1.*values for"):
        rfta.reconstruct(sdf=lambda p: np.zeros(len(p) + 1), budget=500)
    with pytest.raises(ValueError):
        rfta.reconstruct(sdf=lambda p: ["not a number"] * len(p), budget=500)
    with pytest.raises(ValueError, match="at least 125"):
        rfta.reconstruct(sdf=torus_sdf, budget=100)
    with pytest.raises(ValueError, match="not both"):
        rfta.reconstruct(np.zeros((4, 4, 4)), sdf=torus_sdf)
    with pytest.raises(ValueError, match="budget needs sdf"):
        rfta.reconstruct(np.zeros((4, 4, 4)), budget=1000)
    with pytest.raises(ValueError, match="callable"):
        rfta.reconstruct(sdf=3.0)


def test_ctrl_c_stops_an_adaptive_run_between_batches():
    started = threading.Event()

    def slow(p):
        started.set()
        time.sleep(0.05)
        return torus_sdf(p)

    t = time.perf_counter()
    with interrupted_after(0.5), pytest.raises(KeyboardInterrupt):
        rfta.reconstruct(sdf=slow, budget=200_000)
    assert started.is_set() and time.perf_counter() - t < 30


def test_warnings_reach_pythons_warnings_and_the_repr_is_short():
    # A torus clamped at 0.3: the check finds the plateaus and says so, as a warning Python
    # shows (and a filter can silence), and in the report.
    S = np.minimum(torus_sdf(grid(16)), 0.3)
    with pytest.warns(rfta.RftaWarning, match="clamped at 0.3"):
        r = rfta.reconstruct(S, bounds=(-1, 1))
    assert any("clamped" in w for w in r.report["warnings"])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.filterwarnings("ignore", category=rfta.RftaWarning)
        rfta.reconstruct(S, bounds=(-1, 1))
    text = repr(r)
    assert text.startswith("Reconstruction(") and len(text) < 300, text
    assert f"{len(r.faces)} faces" in text and "genus 1" in text, text


def test_a_callable_may_answer_with_a_tensor_on_any_device():
    # A stand-in for a PyTorch tensor on a GPU with gradients: numpy cannot take it as it is.
    class Tensor:
        def __init__(self, values, device="cuda"):
            self.values, self.device = values, device

        def detach(self):
            return Tensor(self.values, self.device)

        def cpu(self):
            return Tensor(self.values, "cpu")

        def numpy(self):
            assert self.device == "cpu", "numpy() of a tensor on a GPU"
            return self.values

        def __array__(self, *_):
            raise TypeError("can't convert cuda tensor to numpy")

    asked = []

    def sdf(p):
        asked.append(len(p))
        return Tensor(np.linalg.norm(p, axis=1) - 0.5)

    r = rfta.reconstruct(sdf=sdf, bounds=(-1, 1), budget=2000)
    assert r.adaptive["evaluations"] == sum(asked) <= 2000
    assert r.report["components"] == 1 and r.report["genus"] == 0


def test_the_mesh_is_simplified_unless_asked_not_to():
    S = torus_sdf(grid(20))
    full = rfta.reconstruct(S, simplify=False)
    r = rfta.reconstruct(S)
    # Same topology, far fewer faces, the unsimplified count in the report.
    assert r.report["faces_unsimplified"] == len(full.faces) > 4 * len(r.faces)
    assert (r.report["genus"], r.report["components"]) == (1, 1)
    assert r.report["sign_errors"] == 0 and r.report["entered"] <= full.report["entered"]
    # Within the tolerance asked (spacings of 2 / 20) of the unsimplified surface, at the
    # simplified mesh's vertices, measured on the torus both meshes approximate.
    tight = rfta.reconstruct(S, simplify_tolerance=0.01)
    assert tight.report["simplify_deviation"] <= 0.01 + 1e-9
    assert len(r.faces) < len(tight.faces) < len(full.faces)
    err = np.abs(torus_sdf(tight.vertices)).max()
    # (plus the unsimplified faces' own sag between their vertices: under 0.01 spacings here)
    assert err <= np.abs(torus_sdf(full.vertices)).max() + 0.02 * 2.0 / 20.0
    # A budget below what the default tolerance keeps (so the budget is what stops it) and
    # above what the samples and the topology allow here (412 faces).
    budget = rfta.reconstruct(S, faces=600)
    assert len(r.faces) > 600
    assert len(budget.faces) <= 600 and budget.report["genus"] == 1
    with pytest.raises(ValueError, match="simplify_tolerance"):
        rfta.reconstruct(S, simplify_tolerance=-1.0)
