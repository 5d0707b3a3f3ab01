"""Cluster-scale runs on Dask: a reliability run split by sample ranges, a line run split
by segments, and a large ``simulate_many`` split by rows. The results equal the
single-machine run bit for bit.

Sample i of a reliability run depends only on (seed, i), so shard k (samples
``[k·shard, (k+1)·shard)``) is the same wherever it runs. Each worker runs shards and sends
back their samples as the bytes of a Parquet file; the client tallies them in order with
the same code (and the same early stop) as one machine. With ``shard_dir`` each shard is
also kept as ``pPPPP-sKKKKKKK.parquet`` there (they concatenate into the run's samples).
A line run goes the same way by segments: both are one kind of job, a study in pieces
seeded by (point, k), each piece handed back under its key to the study's own run.

Locally::

    from dask.distributed import Client, LocalCluster
    import divertsim, divertsim.dask
    client = Client(LocalCluster(n_workers=2, threads_per_worker=1))
    r = divertsim.dask.reliability("configs/mix/hub.toml", client=client,
                                   samples=200_000, shard=5_000)

On a real cluster (every worker with the ``divertsim`` wheel installed)::

    dask scheduler                                 # on the scheduler host, port 8786
    dask worker tcp://SCHEDULER:8786 --nworkers 1 --nthreads 1   # on each worker host
    client = Client("tcp://SCHEDULER:8786")

A worker runs one shard at a time on all its cores (``threads`` per task, default: the
worker's cores), so start one worker process per host. Files a scenario names
(``mix.records``) must be readable at the same path on every worker.
"""

from __future__ import annotations

import functools as _functools
import json as _json
import os as _os
from typing import Any, Mapping, Optional, Sequence

from . import _call, _native, _override_pairs, _scenario_arg
from .analyses import Analysis, _frame, _options_json, _table

__all__ = ["line", "reliability", "simulate_many"]


@_functools.lru_cache(maxsize=8)
def _job(name: str, scenario_toml: str, options_json: str) -> Any:
    """A worker's job, built once per process for each run it serves."""
    return _native.study_job(name, scenario_toml, [], options_json, True)


def _run_piece(
    name: str, scenario_toml: str, options_json: str, point: int, k: int, threads: Optional[int]
) -> Any:
    key, data = _job(name, scenario_toml, options_json).run_piece(point, k, threads)
    return key, bytes(data)


def _study(
    name: str,
    scenario: Any,
    overrides: Optional[Mapping[str, Any]],
    options: Mapping[str, Any],
    allow_outside_paths: bool,
    client: Any,
    threads: Optional[int],
) -> Any:
    """A study's pieces run by the workers of ``client`` (the scenario checked here first: a
    bad one raises ScenarioError before any task is sent): the job, its pieces and what
    each gave back, in order."""
    options_json = _options_json(options)
    job = _call(
        _native.study_job,
        name,
        _scenario_arg(scenario),
        _override_pairs(overrides, {}),
        options_json,
        allow_outside_paths,
    )
    scenario_toml = job.scenario_toml()
    # The workers load the resolved scenario: the same points, without the overrides
    # (already in it), and no file it names need exist on them.
    pieces = job.pieces()
    c = _client(client)
    futures = [
        c.submit(_run_piece, name, scenario_toml, options_json, p, k, threads, pure=False)
        for p, k in pieces
    ]
    return job, pieces, c.gather(futures)


def _many_block(block: Any, offset: int, threads: Optional[int], base: Any) -> Any:
    """One block of a cluster's simulate_many; an invalid row is named by its place in the
    whole table."""
    from . import ScenarioError, simulate_many

    try:
        return simulate_many(block, threads=threads, base=base)
    except ScenarioError as e:
        rows = [r + offset for r in e.rows]
        message = str(e)
        if e.row is not None:
            message = message.replace(f"scenario {e.row}:", f"scenario {e.row + offset}:", 1)
        error = ScenarioError(message, e.problems, None if e.row is None else e.row + offset, rows)
    raise error


def _client(client: Any) -> Any:
    if client is not None:
        return client
    from dask.distributed import get_client

    return get_client()


def reliability(
    scenario: Any = None,
    overrides: Optional[Mapping[str, Any]] = None,
    *,
    client: Any = None,
    threads: Optional[int] = None,
    shard_dir: Optional[str] = None,
    allow_outside_paths: bool = False,
    **options: Any,
) -> Analysis:
    """:func:`divertsim.reliability` with its shards run by the workers of ``client``
    (default: the current Dask client). Same options, same result bit for bit.

    The scenario is checked here first (a bad one raises ScenarioError before any task
    is sent); the workers load its resolved form, so relative paths and ``base`` files
    need not exist on them. ``until_ci`` stops the tally where one machine would, but
    every shard up to ``samples`` is run.
    """
    job, pieces, parts = _study(
        "reliability", scenario, overrides, options, allow_outside_paths, client, threads
    )
    if shard_dir is not None:
        _os.makedirs(shard_dir, exist_ok=True)
        for (p, k), (_, b) in zip(pieces, parts):
            with open(_os.path.join(shard_dir, f"p{p:04}-s{k:07}.parquet"), "wb") as f:
                f.write(b)
    summary, tables, text = job.merge(parts)
    return Analysis(
        name="reliability",
        summary=_json.loads(summary),
        tables={n: _frame(bytes(t)) for n, t in tables},
        text=text,
    )


def line(
    scenario: Any = None,
    overrides: Optional[Mapping[str, Any]] = None,
    *,
    client: Any = None,
    threads: Optional[int] = None,
    allow_outside_paths: bool = False,
    **options: Any,
) -> Analysis:
    """:func:`divertsim.line` with its segments run by the workers of ``client`` (default:
    the current Dask client). Same options, same result bit for bit.

    Segment k (parcels ``[k·segment, (k+1)·segment)``, an empty belt and arms at rest at its
    start) is the same wherever it runs; the workers send back each segment's parcels and
    the client tallies them in order with the code of one machine. The scenario is checked
    here first (a bad one raises ScenarioError before any task is sent).
    """
    job, _, parts = _study("line", scenario, overrides, options, allow_outside_paths, client, threads)
    summary, tables, text = job.merge(parts)
    return Analysis(
        name="line",
        summary=_json.loads(summary),
        tables={n: _table(n, bytes(t)) for n, t in tables},
        text=text,
    )


def simulate_many(
    scenarios: Any,
    *,
    client: Any = None,
    partitions: Optional[int] = None,
    threads: Optional[int] = None,
    base: Any = None,
) -> Any:
    """:func:`divertsim.simulate_many` over the workers of ``client``: the rows split into
    ``partitions`` contiguous blocks (default: 4 per worker), each run by a worker, the
    tables concatenated in order. Equal, row for row and bit for bit, to one machine's.
    """
    import pandas as pd

    c = _client(client)
    n = len(scenarios)
    if partitions is None:
        partitions = max(1, 4 * len(c.scheduler_info().get("workers", {})))
    partitions = max(1, min(partitions, n))
    bounds = [n * i // partitions for i in range(partitions + 1)]
    if isinstance(scenarios, pd.DataFrame):
        blocks: Sequence[Any] = [scenarios.iloc[a:b] for a, b in zip(bounds, bounds[1:])]
    else:
        blocks = [list(scenarios[a:b]) for a, b in zip(bounds, bounds[1:])]
    futures = [
        c.submit(_many_block, blk, a, threads, base, pure=False) for blk, a in zip(blocks, bounds)
    ]
    frames = c.gather(futures)
    out = pd.concat(frames)
    # Columns as one machine's table has them (a frame that crossed processes may come back
    # with strings as plain objects).
    out = pd.DataFrame({c: out[c].tolist() for c in out.columns}, index=out.index)
    if not isinstance(scenarios, pd.DataFrame):
        out = out.reset_index(drop=True)
    return out
