"""Dask: a LocalCluster of 2 workers gives the single-process run bit for bit."""

import json

import pandas as pd
import pytest

import divertsim

distributed = pytest.importorskip("dask.distributed")
import divertsim.dask  # noqa: E402

HUB = "configs/mix/hub.toml"


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_reliability_on_two_workers_equals_one_process(client, tmp_path):
    options = dict(samples=900, shard=200, bins=4, sweep={"machine.belt_speed": [1.8, 2.2]})
    one = divertsim.reliability(HUB, {"machine.cycle_time": 1.3}, **options)
    shards = tmp_path / "shards"
    many = divertsim.dask.reliability(
        HUB, {"machine.cycle_time": 1.3}, client=client, shard_dir=str(shards), **options
    )
    assert many.summary == one.summary
    pd.testing.assert_frame_equal(
        many.tables["failure_rates.csv"], one.tables["failure_rates.csv"], check_exact=True
    )
    # 2 points × 5 shards (the last one short), kept as Parquet that merges to every sample.
    files = sorted(shards.glob("*.parquet"))
    assert len(files) == 10
    samples = pd.concat(pd.read_parquet(f) for f in files)
    assert len(samples) == 2 * 900
    assert list(samples.groupby("point")["sample"].max()) == [899, 899]
    # The sweep really ran two settings.
    points = one.summary["points"]
    assert [p["setting"]["belt_speed_m_s"] for p in points] == [1.8, 2.2]
    assert points[0]["max_overload_ratio"] != points[1]["max_overload_ratio"]


def test_line_on_two_workers_equals_one_process(client):
    options = dict(parcels=360, segment=60, sweep={"line.gap_target": [0.8, 1.6]})
    one = divertsim.line("configs/paper/line_two.toml", **options)
    many = divertsim.dask.line("configs/paper/line_two.toml", client=client, **options)
    assert many.summary == one.summary
    assert many.text == one.text
    pd.testing.assert_frame_equal(many.tables["line.csv"], one.tables["line.csv"], check_exact=True)
    pd.testing.assert_frame_equal(
        many.tables["line_parcels.parquet"], one.tables["line_parcels.parquet"], check_exact=True
    )
    # Two settings, really run: the shorter gap brings more parcels per hour.
    a, b = one.summary["points"]
    assert a["arrival_rate_per_h"] > b["arrival_rate_per_h"]


def test_reliability_early_stop_is_that_of_one_machine(client):
    options = dict(samples=1000, shard=200, until_ci=0.2)
    one = divertsim.reliability(HUB, **options)
    many = divertsim.dask.reliability(HUB, client=client, **options)
    assert many.summary == one.summary
    assert one.summary["points"][0]["stopped_early"] is True


def test_a_bad_scenario_fails_on_the_client_before_any_task(client):
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.dask.reliability(HUB, {"machine.belt_speed": -1.0}, client=client, samples=100)
    assert e.value.problems[0][0] == "machine.belt_speed"


def test_simulate_many_over_the_cluster_equals_one_process(client):
    df = pd.DataFrame(
        {
            "machine.belt_speed": [1.2 + 0.05 * i for i in range(24)],
            "parcel.angle_deg": [(-1) ** i * 0.7 * i for i in range(24)],
        }
    )
    one = divertsim.simulate_many(df)
    many = divertsim.dask.simulate_many(df, client=client, partitions=5)
    pd.testing.assert_frame_equal(many, one, check_exact=True)
    # An invalid row is named by its place in the whole table, not in its block.
    bad = df.copy()
    bad.loc[17, "machine.belt_speed"] = -1.0
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.dask.simulate_many(bad, client=client, partitions=5)
    assert e.value.row == 17 and e.value.rows == [17]
    assert "scenario 17:" in str(e.value)


def test_merge_refuses_shards_of_another_run():
    from divertsim import _native

    options = '{"samples": 300, "shard": 100, "sweep": {"machine.belt_speed": [1.8, 2.2]}}'
    job = _native.study_job("reliability", HUB, [], options)
    other = _native.study_job(
        "reliability", HUB, [], options.replace('"samples"', '"seed": 99, "samples"')
    )
    pieces = [job.run_piece(p, k, 1) for p, k in job.pieces()]
    assert len(pieces) == 6 and len({key for key, _ in pieces}) == 6
    one = divertsim.reliability(
        HUB, samples=300, shard=100, sweep={"machine.belt_speed": [1.8, 2.2]}
    )
    assert json.loads(job.merge(pieces, 1)[0]) == one.summary
    # A shard's bytes under the key of the other point's: its samples are not of that point.
    swapped = [(key, pieces[(i + 3) % 6][1]) for i, (key, _) in enumerate(pieces)]
    with pytest.raises(RuntimeError, match="not of point"):
        job.merge(swapped, 1)
    # Another run's pieces have other keys: refused before anything runs.
    foreign = [other.run_piece(p, k, 1) for p, k in other.pieces()]
    with pytest.raises(ValueError, match="is not one of this run's"):
        job.merge(foreign, 1)
    with pytest.raises(ValueError, match="given twice"):
        job.merge(pieces + pieces[:1], 1)
    with pytest.raises(ValueError, match="no shard 5"):
        job.run_piece(0, 5, 1)
    with pytest.raises(ValueError, match="no study named"):
        _native.study_job("capacity", HUB, [], "{}")
    with pytest.raises(Exception):
        job.merge([(pieces[0][0], b"not parquet")], 1)
