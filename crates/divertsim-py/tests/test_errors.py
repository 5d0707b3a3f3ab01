"""Invalid input: ScenarioError (a ValueError) listing every problem as the CLI does."""

import pandas as pd
import pytest

import divertsim


def cli_problem_lines(cli, *sets):
    args = ["simulate"]
    for s in sets:
        args += ["--set", s]
    code, _, err = cli(*args, "--json")
    assert code == 2
    assert err.startswith("error: ")
    return err[len("error: "):].rstrip("\n")


def test_bad_key_and_range_list_every_problem(cli):
    with pytest.raises(divertsim.ScenarioError) as info:
        divertsim.simulate(machine__belt_speed=-1.0, machine__bogus=3, parcel__mass=0.0)
    e = info.value
    assert isinstance(e, ValueError)
    keys = [k for k, _ in e.problems]
    assert "machine.bogus" in keys and "machine.belt_speed" in keys and "parcel.mass" in keys
    assert len(e.problems) == 3
    text = cli_problem_lines(
        cli, "machine.belt_speed=-1.0", "machine.bogus=3", "parcel.mass=0.0"
    )
    assert str(e) == text
    assert "invalid input: 3 problems" in str(e)
    speed = dict(e.problems)["machine.belt_speed"]
    assert "allowed" in speed or "[" in speed  # names the allowed range


def test_out_of_range_names_the_range(cli):
    with pytest.raises(ValueError) as info:
        divertsim.simulate({"parcel": {"offset": 5.0}})
    assert str(info.value) == cli_problem_lines(cli, "parcel.offset=5.0")
    assert info.value.problems[0][0] == "parcel.offset"


def test_wrong_type_and_unsupported_value(cli):
    with pytest.raises(divertsim.ScenarioError) as info:
        divertsim.simulate(machine__belt_speed="fast")
    assert str(info.value) == cli_problem_lines(cli, 'machine.belt_speed="fast"')
    with pytest.raises(divertsim.ScenarioError, match="machine.belt_speed: a value of type object"):
        divertsim.simulate(machine__belt_speed=object())


def test_missing_file_and_bad_scenario_type():
    with pytest.raises(divertsim.ScenarioError, match="cannot read the scenario file"):
        divertsim.simulate("no/such/file.toml")
    with pytest.raises(TypeError):
        divertsim.simulate(3.0)


def test_simulate_many_names_the_invalid_row():
    rows = [{"machine.belt_speed": 1.5}, {"machine.belt_speed": -2.0}, {}, {"parcel.mass": -1.0}]
    with pytest.raises(divertsim.ScenarioError) as info:
        divertsim.simulate_many(rows)
    e = info.value
    assert e.row == 1 and e.rows == [1, 3]
    assert str(e).startswith("scenario 1: invalid input: 1 problem")
    assert e.problems[0][0] == "machine.belt_speed"
    df = pd.DataFrame({"machine.belt_speed": [1.5, 2.0, 99.0]})
    with pytest.raises(divertsim.ScenarioError, match="scenario 2: "):
        divertsim.simulate_many(df)


def test_threads_zero_is_refused():
    with pytest.raises(ValueError, match="threads"):
        divertsim.simulate_many([None], threads=0)


def test_scenario_error_pickles_whole():
    import pickle

    with pytest.raises(divertsim.ScenarioError) as info:
        divertsim.simulate_many([{}, {"parcel.mass": -1.0}])
    again = pickle.loads(pickle.dumps(info.value))
    assert isinstance(again, divertsim.ScenarioError)
    assert (str(again), again.problems, again.row, again.rows) == (
        str(info.value),
        info.value.problems,
        1,
        [1],
    )
