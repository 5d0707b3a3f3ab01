"""Many runs: equal to the CLI bit for bit, independent of the thread count."""

import math

import numpy as np
import pandas as pd
import pytest

import divertsim

FLOAT_COLUMNS = {
    "max_lateral_m": lambda j: j["max_lateral"],
    "max_impulse_n_s": lambda j: j["max_impulse"],
    "fall_impulse_n_s": lambda j: j["fall_impulse"],
    "overload_ratio": lambda j: j["overload_ratio"],
    "equivalent_drop_height_m": lambda j: j["equivalent_drop_height"],
    "energy_ratio": lambda j: j["energy_ratio"],
    "arm_max_impulse_n_s": lambda j: j["arm_max_impulse"],
    "arm_total_impulse_n_s": lambda j: j["arm_total_impulse"],
    "end_time_s": lambda j: j["final"]["t"],
    "final_x_m": lambda j: j["final"]["x"],
    "final_y_m": lambda j: j["final"]["y"],
    "final_phi_deg": lambda j: j["final"]["phi_deg"],
    "final_vx_m_s": lambda j: j["final"]["vx"],
    "final_vy_m_s": lambda j: j["final"]["vy"],
    "final_omega_rad_s": lambda j: j["final"]["omega"],
    "start_position_m": lambda j: j["scenario"]["machine"]["start_position"],
    "first_impact_s": lambda j: j["impacts"][0]["t"] if j["impacts"] else math.nan,
}


def varied(n, seed=13):
    """n scenarios over the default, spread over valid ranges (full-precision floats)."""
    rng = np.random.default_rng(seed)
    return pd.DataFrame(
        {
            "machine.belt_speed": rng.uniform(1.0, 2.6, n),
            "machine.cycle_time": rng.uniform(1.1, 1.6, n),
            "parcel.offset": rng.uniform(0.0, 0.25, n),
            "parcel.angle_deg": rng.uniform(-30.0, 30.0, n),
            "parcel.mass": rng.uniform(0.5, 15.0, n),
            "materials.arm_friction": rng.uniform(0.1, 0.5, n),
        }
    )


@pytest.fixture(scope="module")
def grid():
    return varied(100)


@pytest.fixture(scope="module")
def table(grid):
    return divertsim.simulate_many(grid, threads=2)


def test_hundred_scenarios_equal_the_cli_bit_for_bit(grid, table, cli_json):
    assert list(table.columns[: grid.shape[1]]) == list(grid.columns)
    assert len(table) == 100
    outcomes = set()
    for i, row in grid.iterrows():
        j = cli_json(sets=list(row.items()))
        t = table.iloc[i]
        assert t["outcome"] == j["outcome"]
        assert t["reason"] == j["reason"] or (j["reason"] is None and pd.isna(t["reason"]))
        assert t["stages"] == " ".join(j["stages"])
        assert t["diverted"] == (j["outcome"] == "diverted")
        assert t["impacts"] == len(j["impacts"])
        assert t["events"] == len(j["events"])
        for col, get in FLOAT_COLUMNS.items():
            a, b = t[col], get(j)
            assert a == b or (math.isnan(a) and math.isnan(b)), (i, col, a, b)
        # The input columns are the scenario's values, exactly.
        assert t["machine.belt_speed"] == j["scenario"]["machine"]["belt_speed"]
        outcomes.add(t["outcome"])
    assert "diverted" in outcomes


def test_thread_count_does_not_change_the_table(grid, table):
    for threads in (1, None):
        other = divertsim.simulate_many(grid, threads=threads)
        pd.testing.assert_frame_equal(other, table, check_exact=True)


def test_list_input_equals_dataframe_input(grid, table):
    rows = grid.head(10).to_dict("records")
    from_list = divertsim.simulate_many(rows, threads=2)
    pd.testing.assert_frame_equal(from_list, table.head(10), check_exact=True)
    nested = [
        {"machine": {"belt_speed": r["machine.belt_speed"]}, "parcel.mass": r["parcel.mass"]}
        for r in rows[:3]
    ]
    t = divertsim.simulate_many(nested)
    assert list(t.columns[:2]) == ["machine.belt_speed", "parcel.mass"]
    for k in range(3):
        one = divertsim.simulate(nested[k])
        assert t["final_x_m"][k] == one.final["x"]


def test_none_paths_base_and_missing_cells():
    base = {"machine": {"belt_speed": 1.6}}
    t = divertsim.simulate_many([None, "configs/default.toml", {"parcel.mass": 9.0}], base=base)
    assert [None if pd.isna(s) else s for s in t["scenario"]] == [None, "configs/default.toml", None]
    assert t["final_x_m"][0] == divertsim.simulate(base).final["x"]
    assert t["final_x_m"][1] == divertsim.simulate().final["x"]
    assert t["final_x_m"][2] == divertsim.simulate(base, parcel__mass=9.0).final["x"]
    df = pd.DataFrame({"parcel.mass": [np.nan, 4.0], "materials.friction_model": [None, "seed"]})
    t = divertsim.simulate_many(df, base=base)
    assert t["final_x_m"][0] == divertsim.simulate(base).final["x"]
    assert t["final_x_m"][1] == divertsim.simulate(
        base, parcel__mass=4.0, materials__friction_model="seed"
    ).final["x"]


def test_dataframe_index_kept_and_integer_columns():
    df = pd.DataFrame({"machine.belt_speed": [2, 1]}, index=[10, 20])
    t = divertsim.simulate_many(df)
    assert list(t.index) == [10, 20]
    assert t["final_x_m"][10] == divertsim.simulate(machine__belt_speed=2).final["x"]
    assert t["diverted"].dtype == bool


def test_the_gil_is_released_while_running():
    import threading
    import time

    grid = varied(1500, seed=5)
    done = threading.Event()
    out = {}

    def work():
        out["t"] = divertsim.simulate_many(grid, threads=1)
        done.set()

    th = threading.Thread(target=work)
    th.start()
    ticks = 0
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    th.join()
    assert len(out["t"]) == 1500
    # With the GIL held for the whole batch this thread would hardly run at all.
    assert ticks > 20, ticks
