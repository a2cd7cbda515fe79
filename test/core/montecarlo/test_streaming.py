"""Streamed Monte Carlo (roe_sep.core.montecarlo.streaming), its statistics and the Dask engine."""

import json
import math

import numpy as np
import pytest

from roe_sep.cli import main
from roe_sep.core.montecarlo import streaming
from roe_sep.core.montecarlo.stats import wilson_interval
from roe_sep.core.montecarlo.sweep import MonteCarloConfig, after_stop, pre_stop, summarize
from roe_sep.core.separation.double_impulse import design
from roe_sep.engine import auto_batch, cluster, ordered_map

D = design()
PS = (0.0, 0.03, 0.06)


def test_wilson_interval_reference_values():
    # Wilson (1927) / Newcombe (1998) Table I: 81 of 263 -> 0.2553 .. 0.3662
    lo, hi = wilson_interval(81, 263)
    assert (lo, hi) == pytest.approx((0.2553, 0.3662), abs=5e-5)
    lo, hi = wilson_interval(0, 1000)
    z2 = 1.959964**2
    assert lo == 0.0 and hi == pytest.approx(z2 / (1000 + z2))
    lo, hi = wilson_interval(1000, 1000)
    assert hi == 1.0 and lo == pytest.approx(1000 / (1000 + z2))
    with pytest.raises(ValueError):
        wilson_interval(3, 2)


def test_block_seed_is_the_spawned_child():
    child = np.random.SeedSequence(7).spawn(4)[3]
    assert np.array_equal(streaming.block_seed(7, 3).generate_state(4), child.generate_state(4))


def _report(chunk, block, mapper=streaming.serial_map, samples=6000, seed=3):
    mc = MonteCarloConfig(samples=samples, seed=seed)
    stats = streaming.stream_sweep(D, mc, PS, chunk, block=block, mapper=mapper)
    rep = streaming.report(stats, mc, chunk, block)
    rep.pop("chunk_size")
    return json.dumps(rep, sort_keys=True)


@pytest.mark.slow
def test_result_identical_for_every_chunk_size_and_worker_count():
    """Same seed, chunks of 1, 3 and 6 blocks (the last block short), in process and on 2 Dask workers: the same
    report to the last digit (counts exact, sums exact)."""
    ref = _report(1000, 1000, samples=5500)
    assert _report(3000, 1000, samples=5500) == ref
    assert _report(6000, 1000, samples=5500) == ref
    with cluster(workers=2) as client:
        two = _report(2000, 1000, samples=5500, mapper=lambda f, items, *a: ordered_map(client, f, items, *a))
    assert two == ref
    assert _report(1000, 1000, samples=5500, seed=4) != ref


@pytest.mark.slow
def test_cli_counts_identical_for_chunks_1e4_and_1e6_and_1_or_2_workers(capsys):
    """The issue's check with the real 10^4-sample block: ``roe-sep mc`` with the same seed, chunks of 10^4 and
    10^6 samples, in process and on 1 and 2 Dask workers: the same counts (and the same report to the last digit).
    25,000 samples: three blocks, the last one short; chunks of 10^6 hold all three, chunks of 10^4 one each."""
    reports = []
    for extra in ([], ["--chunk-size", "1000000"], ["--workers", "1"], ["--workers", "2"],
                  ["--workers", "2", "--chunk-size", "1000000"]):
        assert main(["mc", "--samples", "25000", "--seed", "5", "--p", "0,0.06", "--json", "--chunk-size", "10000",
                     *extra]) == 0
        rep = json.loads(capsys.readouterr().out)
        for key in ("chunk_size", "workers", "scheduler"):
            rep.pop(key)
        reports.append(rep)
    counts = [[{k: v for k, v in row.items() if k.startswith("n_")} for row in r["rows"]] for r in reports]
    assert all(c == counts[0] for c in counts[1:])
    assert counts[0][0]["n_approach"] > 0
    assert all(json.dumps(r, sort_keys=True) == json.dumps(reports[0], sort_keys=True) for r in reports[1:])


def test_streamed_rows_are_the_sweep_summaries_of_the_same_draws():
    mc = MonteCarloConfig(samples=4000, seed=11)
    stats = streaming.stream_sweep(D, mc, PS, 2000, block=1000)
    d, _ = streaming.chunk_draws(D, mc, 0, 4, 1000)
    pre = pre_stop(D, mc, d)
    for p, rs in zip(PS, stats.rows):
        row, ref = rs.row(), summarize(D, mc, p, after_stop(D, mc, d, pre, p))
        for key, value in ref.items():
            assert row[key] == pytest.approx(value, rel=1e-12, abs=1e-12), key
        assert row["n_approach"] == ref["n_approach"]
        assert row["n_below_radar_horizon"] == round(ref["p_below_radar_horizon"] * 4000)
        lo, hi = row["p_approach_ci95"]
        assert lo <= row["p_approach"] <= hi
    assert stats.crossing_min == pytest.approx(float(np.min(pre.crossing)))
    assert int(stats.crossing_hist.sum()) == 4000


def test_chunk_size_must_be_a_multiple_of_the_block(capsys):
    assert main(["mc", "--samples", "20000", "--chunk-size", "15000"]) == 2
    assert "--chunk-size" in capsys.readouterr().err


def test_mc_json_has_counts_and_intervals_for_every_probability(capsys):
    assert main(["mc", "--samples", "3000", "--p", "0,0.06", "--json"]) == 0
    rep = json.loads(capsys.readouterr().out)
    for row in rep["rows"]:
        for key in [k for k in row if k.startswith("p_") and not k.endswith("_ci95")]:
            name = key[2:]
            assert row[f"n_{name}"] == round(row[key] * 3000)
            lo, hi = row[f"{key}_ci95"]
            assert 0.0 <= lo <= row[key] <= hi <= 1.0
    assert rep["block_size"] == streaming.BLOCK_SIZE and rep["samples"] == 3000
    assert sum(rep["histograms"]["crossing"]["counts"]) + rep["histograms"]["crossing"]["below"] \
        + rep["histograms"]["crossing"]["above"] == 3000


def _square(x, offset):
    return x * x + offset


def _fail(x):
    if x == 3:
        raise ArithmeticError("item 3")
    return x


def _worker_setting(key):
    import dask

    return dask.config.get(key)


@pytest.mark.slow
def test_ordered_map_in_process_and_errors():
    assert list(ordered_map(None, _square, range(5), 1)) == [1, 2, 5, 10, 17]
    assert sorted(ordered_map(None, _square, range(3), 0, ordered=False)) == [(0, 0), (1, 1), (2, 4)]
    with pytest.raises(ArithmeticError):
        list(ordered_map(None, _fail, range(5)))
    with cluster(workers=2) as client:
        for batch in (1, 2, 3, 7):
            assert list(ordered_map(client, _square, range(7), 1, batch=batch)) == [x * x + 1 for x in range(7)]
            assert sorted(ordered_map(client, _square, range(7), 0, ordered=False, batch=batch)) == \
                [(x, x * x) for x in range(7)]
        with pytest.raises(ArithmeticError):
            list(ordered_map(client, _fail, range(5), batch=2))
        assert auto_batch(client, 5000) == 78 and auto_batch(client, 10) == 1 and auto_batch(None, 5000) == 1
        # the embedded cluster's workers run without what only a dashboard shows (engine.QUIET)
        assert set(client.run(_worker_setting, "distributed.worker.profile.enabled").values()) == {False}
        assert set(client.run(_worker_setting, "distributed.admin.system-monitor.disk").values()) == {False}
    with pytest.raises(ValueError, match="exclude"):
        with cluster(workers=2, scheduler="tcp://127.0.0.1:1"):
            pass
    with pytest.raises(ValueError, match="--scheduler"):
        with cluster(scheduler="tcp://127.0.0.1:1", connect_timeout=1.0):
            pass


def test_exact_sum_is_order_free():
    rng = np.random.default_rng(0)
    x = rng.normal(size=500) * 10.0 ** rng.integers(-8, 8, 500)
    a, b = streaming.ExactSum(), streaming.ExactSum()
    for v in x:
        a.add(v)
    for part in np.array_split(x[::-1], 7):
        s = streaming.ExactSum()
        for v in part:
            s.add(v)
        b.merge(s)
    assert a.value() == b.value() == math.fsum(x)


def test_allocator_tuning_is_idempotent_and_changes_no_number():
    from roe_sep.core.montecarlo.allocator import keep_freed_memory

    first = keep_freed_memory()
    assert keep_freed_memory() is first  # once per process
    assert _report(2000, 1000, samples=3000) == _report(3000, 1000, samples=3000)
