"""A reliability run on a Dask cluster equals the run on one machine, bit for bit.

    pip install ./crates/divertsim-py "dask[distributed]"
    python examples/python_dask.py        # from the repository root

Replace the LocalCluster with Client("tcp://SCHEDULER:8786") for a real cluster
(crates/divertsim-py/README.md has the commands).
"""

from dask.distributed import Client, LocalCluster

import divertsim
import divertsim.dask

if __name__ == "__main__":
    with LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
        with Client(cluster) as client:
            options = dict(samples=20_000, shard=2_000, sweep={"machine.belt_speed": [1.8, 2.2]})
            on_cluster = divertsim.dask.reliability("configs/mix/hub.toml", client=client, **options)
            here = divertsim.reliability("configs/mix/hub.toml", **options)
            assert on_cluster.summary == here.summary
            for p in on_cluster.summary["points"]:
                d = p["divert_rate"]
                print(
                    f"v = {p['setting']['belt_speed_m_s']} m/s: divert rate {d['estimate']:.5f} "
                    f"[{d['lower']:.5f}, {d['upper']:.5f}], max S/S_fall {p['max_overload_ratio']:.3f}"
                )
            print(on_cluster.tables["failure_rates.csv"].head())
