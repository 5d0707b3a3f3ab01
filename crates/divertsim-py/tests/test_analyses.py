"""The analyses: the same summary and tables as the CLI's commands, checked options."""

import json

import pandas as pd
import pytest

import divertsim

FIG06 = "configs/paper/fig06.toml"
HUB = "configs/mix/hub.toml"


def without_timing(value):
    """A summary without its measured wall times (the only numbers that may differ)."""
    if isinstance(value, dict):
        return {
            k: without_timing(v)
            for k, v in value.items()
            if k not in ("seconds", "wall_seconds", "elapsed_s", "wall_time_s")
        }
    if isinstance(value, list):
        return [without_timing(v) for v in value]
    return value


def read_exact(path):
    """A CSV with its floats bit for bit (round trip: the default from pandas 3 on)."""
    if int(pd.__version__.split(".")[0]) >= 3:
        return pd.read_csv(path)
    return pd.read_csv(path, float_precision="round_trip")


def cli_out(cli, tmp_path, *args):
    """Run a CLI command with --json and --out; (summary, {csv name: DataFrame})."""
    out = tmp_path / "out"
    code, stdout, err = cli(*args, "--json", "--out", out, "--quiet")
    assert code == 0, err
    tables = {p.name: read_exact(p) for p in sorted(out.glob("*.csv"))}
    return json.loads(stdout), tables


def test_trigger_equals_the_cli(cli, tmp_path):
    a = divertsim.trigger(FIG06, speeds=[0.65, 1.3, 2.0])
    summary, tables = cli_out(cli, tmp_path, "trigger", FIG06, "--speeds", "0.65,1.3,2.0")
    assert a.summary == summary
    pd.testing.assert_frame_equal(a.table, tables["trigger.csv"], check_exact=True)
    assert abs(a.table["start_position_m"][0] - 0.8) < 2e-3


def test_the_readable_report_is_the_cli_table(cli, tmp_path):
    # One text for every edge: the api's report, printed by the CLI without --json.
    for name, flag, args in [
        ("trigger", "trigger", ["--speeds", "0.65,1.3"]),
        ("capacity", "capacity", ["--worst", "paper", "--cycle-times", "1.2,1.3",
                                  "--light-barriers", "0,0.3", "--speeds", "1.5,2.0"]),
    ]:
        options = {"speeds": [0.65, 1.3]} if name == "trigger" else {
            "worst": "paper", "cycle_times": [1.2, 1.3], "light_barriers": [0, 0.3],
            "speeds": [1.5, 2.0]}
        a = getattr(divertsim, name)(FIG06, **options)
        code, stdout, err = cli(flag, FIG06, *args, "--quiet")
        assert code == 0, err
        assert a.text == stdout and str(a) == stdout
        assert a.text.strip()


def test_overload_with_options_and_overrides_equals_the_cli(cli, tmp_path):
    a = divertsim.overload(
        FIG06,
        {"machine.cycle_time": 1.2},
        speeds=[1.0, 1.5, 2.0],
        drop_heights=(0.25,),
    )
    summary, tables = cli_out(
        cli,
        tmp_path,
        "overload",
        FIG06,
        "--set",
        "machine.cycle_time=1.2",
        "--speeds",
        "1.0,1.5,2.0",
        "--drop-heights",
        "0.25",
    )
    assert a.summary == summary
    pd.testing.assert_frame_equal(a.table, tables["overload.csv"], check_exact=True)
    assert a.summary["scenario"]["machine"]["cycle_time"] == 1.2


def test_optimize_equals_the_cli_but_for_wall_time(cli, tmp_path):
    a = divertsim.optimize(
        FIG06, method="ga", population=6, generations=2, worst="paper", seed=3
    )
    summary, tables = cli_out(
        cli,
        tmp_path,
        "optimize",
        FIG06,
        "--method",
        "ga",
        "--population",
        "6",
        "--generations",
        "2",
        "--worst",
        "paper",
        "--seed",
        "3",
    )
    assert without_timing(a.summary) == without_timing(summary)
    pd.testing.assert_frame_equal(
        a.tables["evaluations.csv"], tables["evaluations.csv"], check_exact=True
    )
    assert set(a.tables) == {"evaluations.csv", "history.csv"}


def test_reliability_equals_the_cli(cli, tmp_path):
    a = divertsim.reliability(HUB, samples=600, shard=200, bins=4)
    summary, tables = cli_out(
        cli, tmp_path, "reliability", HUB, "--samples", "600", "--shard", "200", "--bins", "4"
    )
    assert a.summary == summary
    pd.testing.assert_frame_equal(
        a.tables["failure_rates.csv"], tables["failure_rates.csv"], check_exact=True
    )
    p = a.summary["points"][0]
    assert p["samples"] == 600
    assert 0.0 <= p["divert_rate"]["estimate"] <= 1.0
    # The arm's side over the mix: the load spectrum as a table, the tipping rate, the
    # largest stroke's scenario (the one the CLI writes as largest_stroke.toml).
    pd.testing.assert_frame_equal(
        a.tables["load_spectrum.csv"], tables["load_spectrum.csv"], check_exact=True
    )
    spectrum = a.tables["load_spectrum.csv"]
    torque = spectrum[spectrum["load"] == "peak_drive_torque_n_m"]
    assert torque["count"].sum() == p["load_spectrum"]["strokes"] == 600
    assert abs(torque["per_million_strokes"].sum() - 1e6) < 1e-6
    assert p["tipping_rate"]["of"] == 600
    largest = p["load_spectrum"]["largest_stroke"]
    again = divertsim.simulate(largest["scenario"])
    assert abs(again.arm_loads["peak_torque"] - largest["peak_drive_torque_n_m"]) <= 1e-6 * largest[
        "peak_drive_torque_n_m"
    ]


LINE_TWO = "configs/paper/line_two.toml"


def test_line_equals_the_cli(cli, tmp_path):
    a = divertsim.line(LINE_TWO, parcels=300, segment=100)
    summary, tables = cli_out(cli, tmp_path, "line", LINE_TWO, "--parcels", "300", "--segment", "100")
    assert a.summary == summary
    pd.testing.assert_frame_equal(a.tables["line.csv"], tables["line.csv"], check_exact=True)
    p = a.summary["points"][0]
    assert p["parcels"] == 300 and len(p["diverters"]) == 2
    log = a.tables["line_parcels.parquet"]
    if not isinstance(log, bytes):  # pyarrow installed: the parcel log as a DataFrame
        assert len(log) == 300
        assert set(log["outcome"]) <= {
            "diverted", "passed", "arm_busy", "not_diverted", "struck_in_passing",
            "wrongly_diverted", "collision", "failed",
        }


def test_the_parcel_log_has_the_streams_own_clock():
    # Issue 50, item 18: arrival_s restarts in every segment; stream_time_s does not.
    a = divertsim.line(LINE_TWO, parcels=300, segment=100)
    log = a.tables["line_parcels.parquet"]
    if isinstance(log, bytes):  # no pyarrow: nothing to read it with
        return
    clock = log["headway_s"].cumsum().shift(1, fill_value=0.0)
    assert (log["stream_time_s"] - clock).abs().max() <= 1e-9 * clock.max()
    assert log["stream_time_s"].is_monotonic_increasing
    assert (log["arrival_s"].iloc[[0, 100, 200]] == 0.0).all()


def test_optimize_for_the_line_equals_the_cli_but_for_wall_time(cli, tmp_path):
    kw = dict(parcels=100, stream_seed=5, population=6, generations=1, polish=False)
    a = divertsim.optimize(LINE_TWO, objective="line", **kw)
    summary, tables = cli_out(
        cli, tmp_path, "optimize", LINE_TWO, "--objective", "line", "--parcels", "100",
        "--stream-seed", "5", "--population", "6", "--generations", "1", "--no-polish",
    )
    assert without_timing(a.summary) == without_timing(summary)
    assert a.summary["objective"] == "line" and a.summary["parcels"] == 100
    pd.testing.assert_frame_equal(
        a.tables["evaluations.csv"], tables["evaluations.csv"], check_exact=True
    )
    assert "throughput_per_h" in a.tables["evaluations.csv"].columns


def test_check_equals_the_cli_and_gives_the_verdict(cli):
    a = divertsim.check("configs/paper/proposed.toml")
    code, stdout, err = cli("check", "configs/paper/proposed.toml", "--json", "--quiet")
    assert code == 4, err  # unsafe
    assert a.summary == json.loads(stdout)
    assert a.summary["verdict"] == "unsafe" and a.summary["overload"]["largest_ratio"] > 1
    assert "verdict: UNSAFE" in a.text
    assert divertsim.check("configs/paper/robust_optimum.toml").summary["verdict"] == "safe"


def test_compare_and_calibrate_equal_the_cli(cli, tmp_path):
    # A synthetic track of the paper's Fig. 13a run, read back by both edges.
    track = tmp_path / "fig13a.csv"
    code, _, err = cli("track", "configs/paper/fig13a.toml", "--synthesize", track)
    assert code == 0, err
    machine = "configs/paper/machine.toml"
    a = divertsim.compare(machine, tracks=[str(track)], allow_outside_paths=True)
    summary, tables = cli_out(
        cli, tmp_path, "compare", machine, "--track", track, "--allow-outside-paths"
    )
    assert a.summary == summary
    assert a.summary["tracks"][0]["matches"] is True
    pd.testing.assert_frame_equal(
        a.tables["comparison.csv"], tables["comparison.csv"], check_exact=True
    )
    c = divertsim.calibrate(
        machine,
        tracks=[str(track)],
        fit="materials.belt_friction",
        budget=40,
        profiles=False,
        allow_outside_paths=True,
    )
    (tmp_path / "out").rename(tmp_path / "compare_out")
    summary, _ = cli_out(
        cli, tmp_path, "calibrate", machine, "--track", track, "--fit",
        "materials.belt_friction", "--budget", "40", "--no-profiles", "--allow-outside-paths",
    )
    assert without_timing(c.summary) == without_timing(summary)
    assert c.text.startswith("calibration on 1 track(s)")
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.compare(machine, tolerance=-1.0)
    assert e.value.problems[0][0] == "tolerance"


def test_bad_options_raise_scenario_errors_naming_them():
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.trigger(FIG06, speeds=[25.0], tolerance=0.5)
    assert isinstance(e.value, ValueError)
    keys = [k for k, _ in e.value.problems]
    assert keys == ["speeds", "tolerance"]
    assert "(0, 20] m/s" in str(e.value)
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.capacity(FIG06, cycle_tiems=[1.2])
    assert e.value.problems[0][0] == "cycle_tiems"
    assert "allowed:" in e.value.problems[0][1] and "cycle_times" in e.value.problems[0][1]
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.optimize(FIG06, method="annealing", bounds={"belt_speed": [3.0, 1.0]})
    keys = [k for k, _ in e.value.problems]
    assert keys[0] == "method" and any(k.startswith("bounds") or "belt_speed" in k for k in keys[1:])
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.overload(FIG06, speeds=[1.0, float("nan")])
    assert e.value.problems[0][0] == "speeds"
    # None is the default; the CLI's value grammar works for lists.
    a = divertsim.trigger(FIG06, speeds="0.65:0.75:0.05", tolerance=None)
    assert a.table["belt_speed_m_s"].tolist() == [0.65, 0.7, 0.75]
    # A bad scenario value is named by its key, as for simulate.
    with pytest.raises(divertsim.ScenarioError) as e:
        divertsim.overload(FIG06, {"machine.belt_speed": -1})
    assert e.value.problems[0][0] == "machine.belt_speed"


def test_analysis_renders_in_a_notebook():
    a = divertsim.trigger(FIG06, speeds=[0.65])
    html = a._repr_html_()
    assert "trigger.csv" in html and "<table" in html
    assert a.to_pandas() is a.table
    # The headline leads: a reliability result's rates with their intervals before any table.
    r = divertsim.reliability(HUB, samples=200, shard=100)
    html = r._repr_html_()
    assert html.index("divert rate") < html.index("overload rate") < html.index("<table")
    assert "Clopper" in html
