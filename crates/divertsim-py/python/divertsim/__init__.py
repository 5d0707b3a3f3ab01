"""divertsim: simulate swing-arm parcel diverters from Python.

The physics, the scenario contract and the pictures are divertsim's Rust library (the
same as the ``divertsim`` command line's): a scenario here validates, runs and reports
exactly as ``divertsim simulate`` does, bit for bit.

>>> import divertsim
>>> r = divertsim.simulate(machine__belt_speed=1.8)
>>> r.outcome
'diverted'
>>> df = divertsim.simulate_many([{"parcel.mass": m} for m in (1.0, 5.0, 15.0)])
>>> list(df["diverted"])
[True, True, True]

SI units throughout; angles in degrees where a name ends in ``_deg`` (the scenario keys,
the table columns), else radians.
"""

from __future__ import annotations

import html as _html
import json as _json
import itertools as _itertools
import os as _os
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

from . import _native

__version__: str = _native.__version__

__all__ = [
    "Result",
    "ScenarioError",
    "preset",
    "presets",
    "simulate",
    "simulate_many",
    "__version__",
]

#: What a scenario may be: None (the built-in default), a path to a TOML file, TOML text
#: (a string with a newline) or a dict nested like the TOML file (dotted keys allowed).
ScenarioLike = Union[None, str, "_os.PathLike[str]", Mapping[str, Any]]


class ScenarioError(ValueError):
    """An invalid scenario: every problem at once, each naming its key and the allowed range.

    ``str(error)`` is the text the command line prints after ``error:``;
    ``error.problems`` is the list of ``(key, message)`` pairs; in ``simulate_many``,
    ``error.row`` is the index of the first invalid scenario and ``error.rows`` every
    invalid one's.

    >>> try:
    ...     divertsim.simulate(machine__belt_speed=-1)
    ... except divertsim.ScenarioError as e:
    ...     print(e.problems[0][0])
    machine.belt_speed
    """

    def __init__(
        self,
        message: str,
        problems: Sequence[Tuple[str, str]] = (),
        row: Optional[int] = None,
        rows: Sequence[int] = (),
    ) -> None:
        super().__init__(message)
        self.problems: List[Tuple[str, str]] = [tuple(p) for p in problems]  # type: ignore[misc]
        self.row: Optional[int] = row
        self.rows: List[int] = list(rows)

    def __reduce__(self) -> Any:  # pickles whole (errors travel from Dask workers)
        return (type(self), (str(self), self.problems, self.row, self.rows))


def _raise(e: Exception) -> "ScenarioError":
    message, problems, row, rows = e.args
    return ScenarioError(message, problems, row, rows)


def _call(fn: Any, *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` with the native ScenarioError as the package's. Raised outside
    the ``except`` block, so it carries no context: Dask's traceback pickling (tblib) would
    otherwise try to pickle the native exception with it."""
    try:
        return fn(*args, **kwargs)
    except _native.ScenarioError as e:
        error = _raise(e)
    raise error


def _scenario_arg(scenario: ScenarioLike) -> Any:
    if scenario is None or isinstance(scenario, Mapping):
        return None if scenario is None else dict(scenario)
    if isinstance(scenario, (str, _os.PathLike)):
        return _os.fspath(scenario)
    raise TypeError(
        "scenario must be None, a path, TOML text or a dict, not " + type(scenario).__name__
    )


def _write_whole(path: Union[str, "_os.PathLike[str]"], text: str) -> None:
    """Write ``text`` to ``path`` whole or not at all: a temporary file beside it, renamed
    over it."""
    target = _os.fspath(path)
    folder = _os.path.dirname(_os.path.abspath(target))
    tmp = _os.path.join(folder, f".{_os.path.basename(target)}.{_os.getpid()}.tmp")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        _os.replace(tmp, target)
    except BaseException:
        if _os.path.exists(tmp):
            _os.remove(tmp)
        raise


def _override_pairs(
    overrides: Optional[Mapping[str, Any]], kwargs: Mapping[str, Any]
) -> List[Tuple[str, Any]]:
    pairs: List[Tuple[str, Any]] = []
    for source in (overrides or {}, kwargs):
        for key, value in source.items():
            pairs.append((key.replace("__", "."), value))
    return pairs


class Result:
    """One run: the verdict, the stages, the strikes, the overload and the trajectory.

    Fields mirror ``divertsim simulate --json`` (``summary``) and ``trajectory.csv``
    (``to_pandas()``). In a notebook the result shows itself as a short summary with the
    top-view figure.
    """

    def __init__(self, native: Any) -> None:
        self._native = native
        #: The JSON summary of ``divertsim simulate --json``, as a dict (floats exact).
        self.summary: Dict[str, Any] = _json.loads(native.summary_json())
        self._trajectory: Optional[Dict[str, Any]] = None

    @property
    def outcome(self) -> str:
        """``"diverted"``, ``"not_diverted"`` or ``"failed"``."""
        return self.summary["outcome"]

    @property
    def diverted(self) -> bool:
        """Whether the parcel's centre crossed the far belt edge."""
        return self.outcome == "diverted"

    @property
    def reason(self) -> Optional[str]:
        """Why not diverted (``"escaped"``, ``"left_on_belt"``, ``"duration_reached"``,
        ``"off_near_side"``, ``"tipped"``, ``"under_arm"``, ``"jammed"``) or why the run
        failed; None when diverted."""
        return self.summary["reason"]

    @property
    def jam(self) -> Optional[dict]:
        """Where and when the parcel jammed (reason ``"jammed"``: wedged between the arm and
        the guide, docs/model.md §6b): ``{"t", "place", "contacts": [{"obstacle", "point"}],
        "cause"}``; None when it did not."""
        return self.summary.get("jam")

    @property
    def stages(self) -> List[str]:
        """The stages visited in order (``"ride"``, ``"F1"`` … ``"F6"``, …)."""
        return list(self.summary["stages"])

    @property
    def events(self) -> List[Dict[str, Any]]:
        """The events in time order: dicts with ``t`` [s] and ``kind``."""
        return list(self.summary["events"])

    @property
    def impacts(self) -> List[Dict[str, Any]]:
        """Every strike in time order: dicts with ``t`` [s], ``stage``, ``obstacle``,
        ``point`` [m], ``normal_impulse``, ``tangential_impulse``, ``impulse`` [N·s],
        ``approach_speed`` [m/s], ``compression_work``, ``dissipated`` [J], ``persistent``,
        ``arm_angular_impulse`` (on the arm about the pivot, N·m·s; None off the arm).
        ``pandas.DataFrame(result.impacts)`` makes a table of them."""
        return list(self.summary["impacts"])

    @property
    def overload(self) -> Dict[str, float]:
        """The overload figures (docs/model.md §5): ``max_impulse`` S and ``fall_impulse``
        S_fall [N·s], ``overload_ratio`` S/S_fall, ``equivalent_drop_height`` H_eq [m],
        ``energy_ratio``, ``arm_max_impulse``, ``arm_total_impulse`` [N·s]."""
        keys = (
            "max_impulse",
            "fall_impulse",
            "overload_ratio",
            "equivalent_drop_height",
            "energy_ratio",
            "arm_max_impulse",
            "arm_total_impulse",
        )
        return {k: self.summary[k] for k in keys}

    @property
    def tipping(self) -> Dict[str, Any]:
        """The tipping check (docs/model.md §12a): ``margin`` (the smallest over the run;
        below 1 the parcel tipped; None if nothing loaded it sideways), ``tipped``, and
        when (``t``), over which ``edge`` and by what ``cause`` (``"forces"`` or
        ``"strike"``) the smallest margin was seen."""
        return dict(self.summary["tipping"])

    @property
    def arm_loads(self) -> Optional[Dict[str, float]]:
        """The arm's side of the stroke (docs/model.md §12b), None without an arm:
        ``peak_torque`` and ``rms_torque`` of the drive at the arm [N·m],
        ``peak_input_torque`` [N·m], ``energy`` per stroke [J], ``peak_contact_torque``
        [N·m], ``max_strike_angular_impulse`` [N·m·s], ``arm_inertia`` [kg·m²]."""
        loads = self.summary["arm_loads"]
        return None if loads is None else dict(loads)

    @property
    def final(self) -> Dict[str, float]:
        """The final state: t [s], x, y [m], phi_deg, vx, vy [m/s], omega [rad/s]."""
        return dict(self.summary["final"])

    @property
    def scenario(self) -> Dict[str, Any]:
        """The resolved scenario (every key, defaults filled in) as a dict."""
        return self.summary["scenario"]

    @property
    def scenario_toml(self) -> str:
        """The resolved scenario as TOML text; ``divertsim simulate FILE`` reruns it."""
        return self._native.scenario_toml()

    @property
    def trajectory(self) -> Dict[str, Any]:
        """The trajectory as numpy float64 arrays of equal length: ``t`` [s], ``x``, ``y``
        [m], ``phi`` [rad], ``vx``, ``vy`` [m/s], ``omega`` [rad/s], ``alpha`` (arm angle,
        rad), ``drive_torque`` (the drive's torque on the arm about the pivot, N·m; NaN
        without an arm), ``contact1_x`` … ``contact2_y`` [m] (NaN without a contact), and
        ``stage`` (a list of str)."""
        if self._trajectory is None:
            self._trajectory = self._native.trajectory()
        return self._trajectory

    def to_pandas(self) -> Any:
        """The trajectory as a pandas DataFrame with the columns of ``trajectory.csv``:
        t_s, x_m, y_m, phi_deg, vx_m_s, vy_m_s, omega_rad_s, alpha_deg, drive_torque_n_m,
        stage, contact1_x_m, contact1_y_m, contact2_x_m, contact2_y_m.

        >>> divertsim.simulate().to_pandas()[["t_s", "x_m", "y_m"]].tail(1)  # doctest: +SKIP
        """
        import numpy as np
        import pandas as pd

        tr = self.trajectory
        return pd.DataFrame(
            {
                "t_s": tr["t"],
                "x_m": tr["x"],
                "y_m": tr["y"],
                "phi_deg": np.degrees(tr["phi"]),
                "vx_m_s": tr["vx"],
                "vy_m_s": tr["vy"],
                "omega_rad_s": tr["omega"],
                "alpha_deg": np.degrees(tr["alpha"]),
                "drive_torque_n_m": tr["drive_torque"],
                "stage": tr["stage"],
                "contact1_x_m": tr["contact1_x"],
                "contact1_y_m": tr["contact1_y"],
                "contact2_x_m": tr["contact2_x"],
                "contact2_y_m": tr["contact2_y"],
            }
        )

    def report(self, path: Union[None, str, "_os.PathLike[str]"] = None) -> str:
        """The animated run report as one self-contained HTML page, the page of
        ``divertsim simulate --report run.html``: the top view played over time with its
        controls, linked plots, the summary and the resolved scenario. It opens offline.

        With ``path`` the page is also written there (whole or not at all: a temporary file
        beside it is renamed over it). Returns the HTML text.

        >>> divertsim.simulate().report("run.html")  # doctest: +SKIP
        """
        html = self._native.report_html()
        if path is not None:
            _write_whole(path, html)
        return html

    def svg(self, width: int = 1000, height: int = 700) -> str:
        """The top view (belt, arm positions, parcel outlines, path of the centre by stage)
        as SVG text, the picture of ``divertsim simulate --plot top.svg``."""
        return self._native.svg(width, height)

    def _repr_html_(self) -> str:
        o = self.overload
        reason = f" ({_html.escape(self.reason)})" if self.reason else ""
        rows = [
            ("outcome", f"<b>{_html.escape(self.outcome)}</b>{reason}"),
            ("stages", _html.escape(" → ".join(self.stages))),
            ("strikes", str(len(self.summary["impacts"]))),
            (
                "overload",
                f"S/S<sub>fall</sub> = {o['overload_ratio']:.3f} "
                f"(S = {o['max_impulse']:.3f} N·s, S<sub>fall</sub> = {o['fall_impulse']:.3f} N·s, "
                f"H<sub>eq</sub> = {o['equivalent_drop_height']:.3f} m)",
            ),
            ("end", f"t = {self.final['t']:.3f} s"),
        ]
        table = "".join(
            f"<tr><th style='text-align:left;padding-right:1em'>{k}</th><td style='text-align:left'>{v}</td></tr>"
            for k, v in rows
        )
        try:
            figure = self.svg(width=700, height=490)
        except ValueError as e:  # a figure that cannot be drawn does not hide the summary
            figure = f"<p>(no figure: {_html.escape(str(e))})</p>"
        return f"<div class='divertsim-result'><table>{table}</table>{figure}</div>"

    def __repr__(self) -> str:
        reason = f" ({self.reason})" if self.reason else ""
        return (
            f"<divertsim.Result {self.outcome}{reason}; stages {' '.join(self.stages)}; "
            f"S/S_fall = {self.overload['overload_ratio']:.4g}>"
        )


def simulate(
    scenario: ScenarioLike = None,
    overrides: Optional[Mapping[str, Any]] = None,
    *,
    allow_outside_paths: bool = False,
    **kwargs: Any,
) -> Result:
    """Run one scenario, as ``divertsim simulate [SCENARIO] --set KEY=VALUE ...`` does.

    ``scenario``: None (the built-in default), a path to a scenario file (its ``base``
    chain and files follow the command line's rules), TOML text, or a dict nested like
    the file (``{"machine": {"belt_speed": 1.8}}``; dotted keys allowed; paths in it are
    relative to the working directory). Overrides use the dotted keys of ``--set``, given
    as ``overrides={"machine.belt_speed": 1.8}``, ``**{"machine.belt_speed": 1.8}`` or
    ``machine__belt_speed=1.8``; values are Python numbers, strings, bools, lists or dicts
    and reach the scenario exactly (no text round trip). Raises ScenarioError (a
    ValueError) listing every problem.

    >>> r = divertsim.simulate("configs/default.toml", machine__belt_speed=1.5)
    >>> r.outcome, r.stages[:2]  # doctest: +SKIP
    ('diverted', ['ride', 'F1'])
    """
    pairs = _override_pairs(overrides, kwargs)
    native = _call(_native.simulate, _scenario_arg(scenario), pairs, allow_outside_paths)
    return Result(native)


def simulate_many(
    scenarios: Any,
    threads: Optional[int] = None,
    base: ScenarioLike = None,
    *,
    allow_outside_paths: bool = False,
    max_sims: int = 10_000_000,
) -> Any:
    """Run many scenarios in parallel and return one pandas DataFrame row per scenario.

    ``scenarios``: a pandas DataFrame whose columns are dotted keys (one row = one
    scenario: its values over ``base``; a NaN or None cell leaves the key unset), or a
    list whose items are None (``base`` itself), dicts (overrides over ``base``, nested
    or dotted) or paths / TOML text (whole scenarios; ``base`` does not apply). Every
    scenario is validated first: an invalid one raises ScenarioError naming its index.
    More than ``max_sims`` scenarios (the CLI's work limit, 10^7) raise ScenarioError
    before any is read. Then all run without the GIL on ``threads`` workers (None: one
    per core, at most 1024; Ctrl-C stops them and raises KeyboardInterrupt); the table
    does not depend on the number of threads, and each row equals
    ``divertsim simulate --json`` of that scenario bit for bit.

    Columns: the override columns, then outcome, reason, stages (space-separated),
    diverted, start_position_m (R_s as run), max_lateral_m, max_impulse_n_s,
    fall_impulse_n_s, overload_ratio, equivalent_drop_height_m, energy_ratio,
    arm_max_impulse_n_s, arm_total_impulse_n_s, end_time_s, final_x_m, final_y_m,
    final_phi_deg, final_vx_m_s, final_vy_m_s, final_omega_rad_s, first_impact_s,
    impacts, events (counts).

    >>> import pandas as pd
    >>> grid = pd.DataFrame({"machine.belt_speed": [1.5, 2.0, 2.5]})
    >>> divertsim.simulate_many(grid, threads=2)[["machine.belt_speed", "outcome"]]  # doctest: +SKIP
    """
    import numpy as np
    import pandas as pd

    base_arg = _scenario_arg(base)

    def too_many(count: str) -> "ScenarioError":
        message = (
            f"{count} scenarios, more than the limit {max_sims:,}: "
            "run fewer at a time, or raise max_sims"
        )
        return ScenarioError(f"invalid input: 1 problem\n  - max_sims: {message}", [("max_sims", message)])

    if isinstance(scenarios, pd.DataFrame):
        if len(scenarios) > max_sims:
            raise too_many(f"{len(scenarios):,}")
        columns = []
        for key in scenarios.columns:
            col = scenarios[key]
            if col.dtype == np.float64:
                values: Any = np.ascontiguousarray(col.to_numpy(dtype=np.float64))
            else:
                values = col.tolist()
            columns.append((str(key), values))
        out = _call(
            _native.simulate_many,
            base_arg,
            columns=columns,
            rows=len(scenarios),
            threads=threads,
            allow_outside_paths=allow_outside_paths,
        )
        head = scenarios.copy()
    else:
        if isinstance(scenarios, (str, bytes, Mapping)) or not hasattr(scenarios, "__iter__"):
            raise TypeError(
                "scenarios must be a pandas DataFrame or a list of scenarios, not "
                + type(scenarios).__name__
            )
        try:
            count = len(scenarios)
        except TypeError:  # an iterator: counted as it is read, up to the limit
            count = None
        if count is not None and count > max_sims:
            raise too_many(f"{count:,}")
        given = list(_itertools.islice(iter(scenarios), max_sims + 1))
        if len(given) > max_sims:
            raise too_many("more than " + f"{max_sims:,}")
        items = [
            it if it is None or isinstance(it, Mapping) else _scenario_arg(it)
            for it in given
        ]
        items = [dict(it) if isinstance(it, Mapping) else it for it in items]
        out = _call(
            _native.simulate_many,
            base_arg,
            scenarios=items,
            threads=threads,
            allow_outside_paths=allow_outside_paths,
        )
        head = _list_head(items, pd)
    result = pd.DataFrame(out)
    result.index = head.index
    return pd.concat([head, result], axis=1)


def _flat(d: Mapping[str, Any], prefix: str = "") -> Iterable[Tuple[str, Any]]:
    for k, v in d.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, Mapping):
            yield from _flat(v, key)
        elif v is not None:
            yield key, v


def _list_head(items: Sequence[Any], pd: Any) -> Any:
    """The override columns of a list of scenarios: every key of the dicts (first seen
    first; None where a scenario does not set it), and ``scenario`` (the path) when any
    item is a file."""
    rows = [dict(_flat(it)) if isinstance(it, Mapping) else {} for it in items]
    keys: Dict[str, None] = {}
    for r in rows:
        for k in r:
            keys.setdefault(k, None)
    data: Dict[str, List[Any]] = {}
    if any(isinstance(it, str) for it in items):
        data["scenario"] = [it if isinstance(it, str) else None for it in items]
    for k in keys:
        data[k] = [r.get(k) for r in rows]
    return pd.DataFrame(data, index=pd.RangeIndex(len(items)))


def presets() -> Dict[str, str]:
    """The built-in scenarios (``configs/`` of the repository): name → description.

    >>> "default" in divertsim.presets()
    True
    """
    return dict(_native.presets())


def preset(name: str, as_dict: bool = False) -> Union[str, Dict[str, Any]]:
    """The built-in scenario ``name`` (``"default"``, ``"paper/fig13a"``) as TOML text, or
    as a dict with ``as_dict=True``. Raises KeyError naming the presets for an unknown
    name. A preset with a ``base`` needs its base beside it: ``divertsim preset --all DIR``
    writes them all.

    >>> r = divertsim.simulate(divertsim.preset("default"))
    """
    text = _native.preset(name)
    return _json.loads(_native.toml_to_json(text)) if as_dict else text


# The analyses (after the helpers above, which they use).
from . import analyses as _analyses  # noqa: E402
from .analyses import (  # noqa: E402
    Analysis,
    calibrate,
    capacity,
    capture,
    check,
    compare,
    line,
    optimize,
    overload,
    reliability,
    trigger,
    worst_case,
)

__all__ += _analyses.__all__
