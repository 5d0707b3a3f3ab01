"""Throughput of divertsim.simulate_many: 10,000 scenarios over the default on 2 threads.

The scenarios are those of the Rust counterpart (crates/divertsim-api/examples/
throughput.rs), built by the same formula in f64 (a golden-ratio sequence, identical
in both languages): scenario i sets

    machine.belt_speed = 1.0 + 1.6 * u(i, 0)      [m/s]
    parcel.offset      = 0.25 * u(i, 1)           [m]
    parcel.angle_deg   = -30.0 + 60.0 * u(i, 2)   [deg]
    parcel.mass        = 0.5 + 14.5 * u(i, 3)     [kg]

with u(i, k) = frac((i + 1) * A[k]), A = (0.6180339887498949, 0.7548776662466927,
0.5698402909980532, 0.8191725133961645). Both print the number diverted and the sum of
final x as a check that they ran the same scenarios.

Usage: python bench_simulate_many.py [N] [THREADS]   (median of 3 timed runs)
"""

import math
import statistics
import sys
import time

import numpy as np
import pandas as pd

import divertsim

A = (0.6180339887498949, 0.7548776662466927, 0.5698402909980532, 0.8191725133961645)


def u(i, k):
    x = (i + 1) * A[k]
    return x - math.floor(x)


def scenarios(n):
    return pd.DataFrame(
        {
            "machine.belt_speed": [1.0 + 1.6 * u(i, 0) for i in range(n)],
            "parcel.offset": [0.25 * u(i, 1) for i in range(n)],
            "parcel.angle_deg": [-30.0 + 60.0 * u(i, 2) for i in range(n)],
            "parcel.mass": [0.5 + 14.5 * u(i, 3) for i in range(n)],
        }
    )


def main():
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 10_000
    threads = int(sys.argv[2]) if len(sys.argv) > 2 else 2
    df = scenarios(n)
    divertsim.simulate_many(df.head(50), threads=threads)  # warm-up
    times = []
    table = None
    for _ in range(3):
        t0 = time.perf_counter()
        table = divertsim.simulate_many(df, threads=threads)
        times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    print(
        f"python simulate_many: {n} scenarios on {threads} threads: "
        f"median {med:.3f} s of {', '.join(f'{t:.3f}' for t in times)} -> {n / med:.0f} scenarios/s"
    )
    print(
        f"check: {int(table['diverted'].sum())} diverted, sum of final x = "
        f"{float(np.sum(table['final_x_m'])):.12e} m"
    )


if __name__ == "__main__":
    main()
