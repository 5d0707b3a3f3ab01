"""Shared fixtures: the repository root and the `divertsim` command line to compare with."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]


def _cli_binary() -> Path:
    """The CLI: $DIVERTSIM_BIN, else a built one under $CARGO_TARGET_DIR (or target/),
    release first, else built now (debug)."""
    env = os.environ.get("DIVERTSIM_BIN")
    if env:
        return Path(env)
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    for profile in ("release", "debug"):
        exe = target / profile / "divertsim"
        if exe.exists():
            return exe
    subprocess.run(
        ["cargo", "build", "-p", "divertsim"], cwd=ROOT, check=True, capture_output=True
    )
    return target / "debug" / "divertsim"


@pytest.fixture(scope="session")
def cli():
    """Run `divertsim ARGS...` from the repository root: (exit code, stdout, stderr)."""
    exe = _cli_binary()

    def run(*args):
        p = subprocess.run(
            [str(exe), *map(str, args)], cwd=ROOT, capture_output=True, text=True
        )
        return p.returncode, p.stdout, p.stderr

    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """`divertsim simulate [SCENARIO] --set k=v ... --json` parsed (floats exact)."""

    def run(scenario=None, sets=()):
        args = ["simulate"]
        if scenario is not None:
            args.append(scenario)
        for k, v in sets:
            args += ["--set", f"{k}={toml_value(v)}"]
        args.append("--json")
        code, out, err = cli(*args)
        assert code == 0, err
        return json.loads(out)

    return run


def toml_value(v):
    """A Python value as TOML text for --set; floats by repr (shortest exact form)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    return str(v)


@pytest.fixture(autouse=True)
def _repo_cwd(monkeypatch):
    """Tests run from the repository root, as the CLI does (relative scenario paths)."""
    monkeypatch.chdir(ROOT)
