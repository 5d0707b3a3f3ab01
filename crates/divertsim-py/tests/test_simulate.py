"""One run: the same as `divertsim simulate --json`, the override spellings, the views."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import divertsim


def test_default_run_equals_the_cli(cli_json):
    r = divertsim.simulate()
    assert r.summary == cli_json()
    assert r.outcome == "diverted"
    assert r.diverted
    assert r.reason is None
    assert r.stages[0] == "ride" and "F1" in r.stages
    assert r.overload["overload_ratio"] == r.summary["overload_ratio"]
    assert r.overload["max_impulse"] == max(i["impulse"] for i in r.impacts)
    assert r.scenario["machine"]["belt_speed"] == 2.0
    assert r.summary["divertsim"]["version"] == divertsim.__version__


def test_override_spellings_agree_and_equal_cli_set(cli_json):
    a = divertsim.simulate(machine__belt_speed=1.7)
    b = divertsim.simulate(**{"machine.belt_speed": 1.7})
    c = divertsim.simulate(overrides={"machine.belt_speed": 1.7})
    d = divertsim.simulate({"machine": {"belt_speed": 1.7}})
    e = divertsim.simulate({"machine.belt_speed": 1.7})
    for other in (b, c, d, e):
        assert other.summary == a.summary
    assert a.summary == cli_json(sets=[("machine.belt_speed", 1.7)])
    default = divertsim.simulate()
    assert a.summary["final"] != default.summary["final"]
    assert a.scenario["machine"]["belt_speed"] == 1.7


def test_exact_floats_reach_the_scenario(cli_json):
    v = 1.2345678901234567
    r = divertsim.simulate(machine__belt_speed=v, parcel__angle_deg=-7.123456789012345)
    assert r.scenario["machine"]["belt_speed"] == v
    assert r.summary == cli_json(
        sets=[("machine.belt_speed", v), ("parcel.angle_deg", -7.123456789012345)]
    )


def test_scenario_file_path_and_text(cli_json):
    path = "configs/paper/fig13a.toml"
    expected = cli_json(path)
    assert divertsim.simulate(path).summary == expected
    assert divertsim.simulate(Path(path)).summary == expected
    text = Path("configs/default.toml").read_text()
    assert divertsim.simulate(text).summary == cli_json("configs/default.toml")


def test_non_numeric_overrides(cli_json):
    sets = {
        "materials.friction_model": "seed",
        "run.arm": True,
        "parcel.velocity": [2.0, 0.1],
        "machine.near_side": "guide",
    }
    r = divertsim.simulate(overrides=sets)
    assert r.summary == cli_json(sets=list(sets.items()))


def test_trajectory_arrays_and_csv(tmp_path, cli):
    r = divertsim.simulate()
    tr = r.trajectory
    n = len(tr["t"])
    assert n > 100
    for k in ("t", "x", "y", "phi", "vx", "vy", "omega", "alpha", "drive_torque", "contact1_x", "contact2_y"):
        assert isinstance(tr[k], np.ndarray), k
        assert tr[k].dtype == np.float64, k
        assert tr[k].shape == (n,), k
    assert len(tr["stage"]) == n
    assert np.all(np.diff(tr["t"]) >= 0)
    assert tr["t"][-1] == r.final["t"]
    # The arm's side: the drive torque beside α, the stroke's loads and the tipping check.
    assert 0 < np.max(np.abs(tr["drive_torque"])) <= r.arm_loads["peak_torque"] * (1 + 1e-9)
    assert r.arm_loads["energy"] > 0
    assert r.tipping["tipped"] is False and r.tipping["margin"] > 1

    code, _, err = cli("simulate", "--out", tmp_path / "run", "--force")
    assert code == 0, err
    csv = pd.read_csv(tmp_path / "run" / "trajectory.csv", engine="python")  # exact floats
    df = r.to_pandas()
    assert list(df.columns) == list(csv.columns)
    pd.testing.assert_frame_equal(df, csv, check_exact=True, check_dtype=False)


def test_repr_html_has_the_figure():
    r = divertsim.simulate(parcel__mass=5.0)
    html = r._repr_html_()
    assert "<svg" in html and "diverted" in html and "S/S<sub>fall</sub>" in html
    assert r.svg().startswith("<svg")
    assert "divertsim.Result diverted" in repr(r)


def test_python_report_is_the_clis_run_report(tmp_path, cli):
    """Result.report writes the page of `divertsim simulate --report`, byte for byte, and
    returns its text; a folder that does not exist is an error that leaves nothing."""
    r = divertsim.simulate(parcel__offset=0.1)
    page = tmp_path / "run.html"
    html = r.report(page)
    assert html.startswith("<!DOCTYPE html>") and "divertsim" in html
    assert page.read_text(encoding="utf-8") == html
    theirs = tmp_path / "cli.html"
    code, _, err = cli("simulate", "--set", "parcel.offset=0.1", "--report", theirs)
    assert code == 0, err
    assert theirs.read_text(encoding="utf-8") == html
    assert r.report() == html
    with pytest.raises(OSError):
        r.report(tmp_path / "missing" / "run.html")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cli.html", "run.html"]


def test_scenario_toml_reruns_the_same(tmp_path):
    r = divertsim.simulate(machine__cycle_time=1.3, parcel__offset=0.1)
    f = tmp_path / "s.toml"
    f.write_text(r.scenario_toml)
    again = divertsim.simulate(str(f))
    assert again.summary["final"] == r.summary["final"]


def test_presets():
    names = divertsim.presets()
    assert "default" in names and "paper/fig13a" in names
    text = divertsim.preset("default")
    a, b = divertsim.simulate(text).summary, divertsim.simulate().summary
    # The file states max_swing_deg, which the built-in default leaves to the drive.
    assert {k: v for k, v in a.items() if k != "scenario"} == {
        k: v for k, v in b.items() if k != "scenario"
    }
    d = divertsim.preset("paper/machine", as_dict=True)
    assert isinstance(d, dict)
    with pytest.raises(KeyError, match="allowed: "):
        divertsim.preset("nope")


def test_adaptive_trigger_matches_cli(cli_json):
    sets = [("machine.trigger", "adaptive"), ("parcel.offset", 0.3)]
    r = divertsim.simulate(overrides=dict(sets))
    assert r.summary == cli_json(sets=sets)
    assert r.summary["trigger"]["kind"] == "adaptive"
    assert not math.isnan(r.summary["trigger"]["start_position"])


def test_version():
    assert isinstance(divertsim.__version__, str) and divertsim.__version__.count(".") == 2


def test_a_wedged_parcel_jams_and_says_where():
    wedge = Path(__file__).resolve().parents[3] / "configs" / "wedge.toml"
    r = divertsim.simulate(wedge)
    assert (r.outcome, r.reason) == ("not_diverted", "jammed")
    assert r.jam == r.summary["jam"]
    assert r.jam["contacts"][0]["obstacle"] == "arm_back"
    assert r.jam["contacts"][-1]["obstacle"] == "guide"
    assert r.jam["place"].startswith("between the arm's back face at (")
    assert r.events[-1] == {"t": r.jam["t"], "kind": "jammed"}
    assert divertsim.simulate().jam is None
