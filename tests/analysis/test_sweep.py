
import numpy as np
import pytest

from pneunet.design import sweep as S
from pneunet.design.circuits import oscillator

FAST = S.OscillationMeasure(t_stop=6.0)  # V = 50 mL: period ≈ 1.5 s


def small_grid(n=3):
    return [dict(p, V=50.0) for p in S.grid(S.lin("Rout", 0.0, 1.5, n), S.lin("Rvent", 2.5, 3.5, n))]


def test_point_generators():
    assert [p["x"] for p in S.grid(S.lin("x", 0, 1, 3))] == [0.0, 0.5, 1.0]
    assert np.allclose(S.log("r", 1, 100, 3).values, [1, 10, 100])
    g = S.grid(S.values("a", [1, 2]), S.values("b", [3, 4, 5]))
    assert len(g) == 6 and g[0] == {"a": 1, "b": 3}
    lhs = S.latin_hypercube({"X1.pclose": S.tolerance(96.42, 5)}, 10, seed=1)
    u = sorted(p["X1.pclose"] for p in lhs)
    # one point per stratum of width 1 kPa
    assert all(91.42 + i <= v < 92.42 + i for i, v in enumerate(u))
    mc = S.monte_carlo({"a": S.tolerance(1.0, 0.1, "normal")}, 200, seed=0)
    assert abs(np.mean([p["a"] for p in mc]) - 1.0) < 0.02
    assert S.point_key({"a": 1.0, "b": 2}) == S.point_key({"b": 2, "a": 1.0})
    assert S.parse_axis("Rout=lin:0:1:5").values[-1] == 1.0


def test_element_and_model_parameters_can_be_swept():
    c = S.apply_overrides(oscillator(), {"Rvent.R": 4.0, "X1.pclose": 90.0, "PH.value": 400})
    assert c.elements["Rvent"].params["R"] == 4.0
    assert c.elements["X1"].params["model"].pclose == 90.0
    assert c.elements["PH"].params["value"].value(0.0) == 400


def failing_build(p):
    if p["Rout"] > 1:
        raise ValueError("no such circuit")
    return oscillator(p)


def test_failed_points_are_recorded_not_fatal():
    pts = [{"Rout": 0.0, "V": 50.0}, {"Rout": 2.0, "V": 50.0}]
    r = S.run_sweep(failing_build, pts, FAST, workers=1, progress=False)
    assert r.failed == 1
    assert r.table["error"].isna().iloc[0]
    assert "no such circuit" in r.table["error"].iloc[1]
    assert r.table["regime"].iloc[0] == "equilibrium"


def test_local_pool_and_dask_give_identical_tables(tmp_path):
    """A dask cluster's sweep equals the local one point for point; its points go in
    batches (fewer tasks than points) and every point reaches the store."""
    distributed = pytest.importorskip("distributed")
    from pneunet.design.sweep_dask import batch_sizes

    pts = small_grid(3)
    local = S.run_sweep(oscillator, pts, FAST, workers=2, progress=False)
    assert local.workers == 2
    store = tmp_path / "cluster.jsonl"
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client, \
            distributed.get_task_stream(client) as tasks:
        remote = S.run_sweep(oscillator, pts, FAST, executor=client, store=store,
                             progress=False)
    a = local.table.drop(columns="elapsed_s")
    b = remote.table.drop(columns="elapsed_s")
    assert a.equals(b)
    assert set(a["regime"]) == {"oscillation", "equilibrium"}
    assert remote.workers == 2
    assert len(tasks.data) == len(batch_sizes(9, 2)) < 9
    stored = S.read_store(store)
    assert set(stored) == set(b["key"])
    assert all(stored[k]["result"]["regime"] == r for k, r in zip(b["key"], b["regime"]))


def test_dask_batches_shrink_towards_the_end():
    from pneunet.design.sweep_dask import batch_sizes

    for n, threads in [(144, 2), (9, 2), (1, 4), (1000, 8)]:
        sizes = batch_sizes(n, threads)
        assert sum(sizes) == n and sizes == sorted(sizes, reverse=True) and sizes[-1] == 1
    assert batch_sizes(144, 2)[:3] == [24, 20, 17]  # 144/6, 120/6, 100/6 rounded up
    assert len(batch_sizes(144, 2)) <= 24  # a few per worker, not 144
    assert batch_sizes(0, 2) == []
