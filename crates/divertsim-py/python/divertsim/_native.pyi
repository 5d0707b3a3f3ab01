"""Type stubs of divertsim._native, the Rust side of the package (use ``divertsim``)."""

from typing import Any, Dict, List, Optional, Sequence, Tuple

__version__: str

class ScenarioError(ValueError):
    """args: (message, [(key, message), ...], row or None, rows)."""

class Run:
    def summary_json(self) -> str: ...
    def scenario_toml(self) -> str: ...
    def svg(self, width: int = 1000, height: int = 700) -> str: ...
    def trajectory(self) -> Dict[str, Any]: ...

def simulate(
    scenario: Any, overrides: Sequence[Tuple[str, Any]], allow_outside_paths: bool = False
) -> Run: ...
def simulate_many(
    base: Any,
    scenarios: Optional[Sequence[Any]] = None,
    columns: Optional[Sequence[Tuple[str, Any]]] = None,
    rows: int = 0,
    threads: Optional[int] = None,
    allow_outside_paths: bool = False,
) -> Dict[str, Any]: ...
def presets() -> List[Tuple[str, str]]: ...
def preset(name: str) -> str: ...
def toml_to_json(text: str) -> str: ...
def analysis(
    name: str,
    scenario: Any,
    overrides: Sequence[Tuple[str, Any]],
    options_json: str,
    threads: Optional[int] = None,
    allow_outside_paths: bool = False,
) -> Tuple[str, List[Tuple[str, bytes]], str]: ...

def registry() -> List[Tuple[str, str, List[str], str]]: ...

class StudyJob:
    def pieces(self) -> List[Tuple[int, int]]: ...
    def scenario_toml(self) -> str: ...
    def run_piece(self, point: int, k: int, threads: Optional[int] = None) -> Tuple[int, bytes]: ...
    def merge(
        self, pieces: Sequence[Tuple[int, bytes]], threads: Optional[int] = None
    ) -> Tuple[str, List[Tuple[str, bytes]], str]: ...

def study_job(
    name: str,
    scenario: Any,
    overrides: Sequence[Tuple[str, Any]],
    options_json: str,
    allow_outside_paths: bool = False,
) -> StudyJob: ...
