"""divertsim from Python in a few lines: one run, its figure, a small parameter study.

Install once from the repository root:  pip install ./crates/divertsim-py
Then run from the repository root:       python examples/python_quickstart.py
"""

import os
import tempfile

import pandas as pd

import divertsim

# One run of the built-in default scenario (the paper's compact parcel at 2 m/s), with the
# belt a little slower: the same keys as `divertsim simulate --set machine.belt_speed=1.8`.
r = divertsim.simulate(machine__belt_speed=1.8)
print(r)
print("stages:", " → ".join(r.stages))
print(f"largest impulse {r.overload['max_impulse']:.3f} N·s = {r.overload['overload_ratio']:.3f} × S_fall")
print(r.to_pandas()[["t_s", "x_m", "y_m", "phi_deg", "stage"]].tail(3))
svg = os.path.join(tempfile.gettempdir(), "divertsim_top_view.svg")
with open(svg, "w") as f:
    f.write(r.svg())  # the top view; in Jupyter, `r` alone shows it inline
print("top view:", svg)

# A parameter study: belt speed × parcel angle, every run in parallel, one row per run.
grid = pd.DataFrame(
    [(v, a) for v in (1.4, 1.8, 2.2, 2.6) for a in (-20.0, 0.0, 20.0)],
    columns=["machine.belt_speed", "parcel.angle_deg"],
)
table = divertsim.simulate_many(grid, threads=2)
print(table[["machine.belt_speed", "parcel.angle_deg", "outcome", "overload_ratio", "end_time_s"]])

# Invalid input names every problem with its key and allowed range.
try:
    divertsim.simulate(machine__belt_speed=-1.0, parcel__mass=0.0)
except divertsim.ScenarioError as e:
    print(e)
