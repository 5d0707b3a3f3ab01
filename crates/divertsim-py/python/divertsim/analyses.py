"""The paper's analyses and divertsim's own, as functions returning an :class:`Analysis`.

Each function runs the same library code as the ``divertsim`` command of the same name
(``divertsim trigger``, ``capacity``, ...): its ``summary`` is the command's ``--json``
object, its ``tables`` are the command's CSV (and Parquet, with pyarrow) files as DataFrames,
column for column, and its
``text`` is what the command prints. The functions of the analyses on the library's contract
(all of them: trigger, capture, overload, worst_case, capacity, optimize, reliability,
line, compare, calibrate) are generated from their options types
(``_analyses.py``, by ``divertsim._codegen``): their keyword arguments, defaults and
docstrings are the CLI's flags, defaults and help.
Options have the names of the command's flags in snake case (``scan_step`` for
``--scan-step``); ranges are ``[lo, hi]`` lists or tuples; a list option is a list or a text
in the CLI's grammar (``speeds="0.65:2.3:0.05"`` gives the flag's numbers exactly); ``None``
is the default; scenario overrides go in ``overrides`` (dotted keys). A bad scenario or option raises :class:`divertsim.ScenarioError`
naming it and its allowed range, before anything runs.

>>> import divertsim
>>> a = divertsim.trigger("configs/paper/fig06.toml", speeds=[0.65, 1.3, 2.0])
>>> a.table[["belt_speed_m_s", "start_position_m"]]  # doctest: +SKIP
"""

from __future__ import annotations

import html as _html
import io as _io
import json as _json
from dataclasses import dataclass, field
from typing import Any, Dict, Mapping, Optional

from . import _call, _native, _override_pairs, _scenario_arg

__all__ = [
    "Analysis",
    "calibrate",
    "capacity",
    "capture",
    "check",
    "compare",
    "line",
    "optimize",
    "overload",
    "reliability",
    "trigger",
    "worst_case",
]


@dataclass
class Analysis:
    """The result of an analysis: its summary and its tables.

    ``summary`` is the ``--json`` object of the command (floats exact, with the divertsim
    version, the units and the resolved scenario); ``tables`` maps the command's CSV file
    names (``"trigger.csv"``) to DataFrames; ``table`` is the first of them; ``text`` is the
    readable report the command prints (also ``str(analysis)``).
    """

    name: str
    summary: Dict[str, Any]
    tables: Dict[str, Any] = field(default_factory=dict)
    text: str = ""

    def __str__(self) -> str:
        return self.text or f"divertsim {self.name}"

    @property
    def table(self) -> Any:
        """The main table (the first CSV the command writes), or None."""
        return next(iter(self.tables.values()), None)

    def to_pandas(self) -> Any:
        """The main table as a DataFrame (the same as :attr:`table`)."""
        return self.table

    def _repr_html_(self) -> str:
        head = f"<b>divertsim {_html.escape(self.name)}</b>"
        parts = [head]
        # The headline first: the command's own readable report (reliability's rates with
        # their intervals, worst_case's poses, check's verdict, ...), then the tables.
        if self.text:
            parts.append(f"<pre>{_html.escape(self.text)}</pre>")
        for n, df in self.tables.items():
            if isinstance(df, bytes):
                parts.append(f"<p><code>{_html.escape(n)}</code>: {len(df)} bytes</p>")
                continue
            parts.append(f"<p><code>{_html.escape(n)}</code>: {len(df)} rows</p>")
            parts.append(df.head(12).to_html(max_cols=12))
        return "\n".join(parts)


def _table(name: str, data: bytes) -> Any:
    """A table file as a DataFrame: CSV always, Parquet (the line's parcel log) when pyarrow
    is installed (``pip install "divertsim[dask]"``), else its bytes."""
    if name.endswith(".parquet"):
        import pandas as pd

        try:
            return pd.read_parquet(_io.BytesIO(data))
        except ImportError:
            return data
    return _frame(data)


def _frame(data: bytes) -> Any:
    import pandas as pd

    # The CSV's floats are written shortest-exact; pandas reads them back bit for bit
    # ("round_trip", the default from pandas 3 on).
    if int(pd.__version__.split(".")[0]) >= 3:
        return pd.read_csv(_io.BytesIO(data))
    return pd.read_csv(_io.BytesIO(data), float_precision="round_trip")


_MAX_DEPTH = 32  # as the scenario values' conversion: deeper is a mistake or a cycle


def _options_json(options: Mapping[str, Any]) -> str:
    """The options as JSON; a NaN or infinite number, a value nested deeper than 32 levels
    (a list that contains itself) or one with no JSON form is a ScenarioError naming its
    option."""
    from . import ScenarioError

    class _Bad(Exception):
        pass

    def plain(v: Any, depth: int) -> Any:
        if depth > _MAX_DEPTH:
            raise _Bad(
                f"nested more than {_MAX_DEPTH} levels deep (a list or dict that contains itself?)"
            )
        if isinstance(v, (tuple, list)):
            return [plain(x, depth + 1) for x in v]
        if isinstance(v, Mapping):
            return {str(k): plain(x, depth + 1) for k, x in v.items()}
        if v is None or isinstance(v, (bool, int, float, str)):
            return v
        if hasattr(v, "tolist"):  # numpy arrays and scalars
            return plain(v.tolist(), depth + 1)
        raise _Bad(
            f"a value of type {type(v).__name__} has no JSON form; "
            "allowed: bool, int, float, str, list, dict"
        )

    def refuse(k: str, message: str) -> "ScenarioError":
        return ScenarioError(f"invalid input: 1 problem\n  - {k}: {message}", [(k, message)])

    out = {}
    for k, v in options.items():
        try:
            out[k] = plain(v, 0)
        except _Bad as e:
            raise refuse(k, str(e)) from None
        except RecursionError:
            raise refuse(k, "nested too deep") from None
        try:
            _json.dumps(out[k], allow_nan=False)
        except ValueError:
            raise refuse(k, "holds a NaN or infinite number; allowed: finite numbers") from None
    return _json.dumps(out)


def run(
    name: str,
    scenario: Any = None,
    overrides: Optional[Mapping[str, Any]] = None,
    *,
    threads: Optional[int] = None,
    allow_outside_paths: bool = False,
    **options: Any,
) -> Analysis:
    """Run the analysis ``name`` (trigger, capture, overload, worst_case, capacity,
    optimize, reliability) with ``options``; the functions below call this.

    ``max_sims`` (an option of every analysis, default 10,000,000) is the work limit, as the
    CLI's ``--max-sims``: a run that needs more simulations whatever its verdicts is refused,
    and one whose count passes it is stopped with a ScenarioError naming ``max_sims``;
    ``threads`` is 1 to 1024 (None: one per core).
    Ctrl-C raises KeyboardInterrupt promptly."""
    summary, tables, text = _call(
        _native.analysis,
        name,
        _scenario_arg(scenario),
        _override_pairs(overrides, {}),
        _options_json(options),
        threads,
        allow_outside_paths,
    )
    return Analysis(
        name=name,
        summary=_json.loads(summary),
        tables={n: _table(n, bytes(b)) for n, b in tables},
        text=text,
    )


# The analyses on the library's contract: generated from their options types (after run and
# Analysis above, which they use).
from ._analyses import (  # noqa: E402
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
