#!/usr/bin/env bash
# The Python package's tests, as CI runs them: a venv under $CARGO_TARGET_DIR/pyenv (or
# target/pyenv), the package built by maturin (release, abi3 wheel) and installed into it,
# the CLI built for the comparisons, then pytest. Needs only the Rust toolchain, python3
# (>= 3.9, with venv) and pip; everything else comes from the package registries.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$root/target}"
venv="$CARGO_TARGET_DIR/pyenv"
wheels="$CARGO_TARGET_DIR/wheels"
start=$SECONDS

if [ ! -x "$venv/bin/python" ]; then
    python3 -m venv "$venv"
fi
py="$venv/bin/python"
"$py" -m pip install --quiet --disable-pip-version-check \
    "maturin>=1.5,<2" "pytest>=7" "numpy>=1.21" "pandas>=1.3" \
    "dask>=2023.1" "distributed>=2023.1" "pyarrow>=10"

rm -rf "$wheels"
"$venv/bin/maturin" build --release --quiet -m crates/divertsim-py/Cargo.toml -o "$wheels" -i "$py"
"$py" -m pip install --quiet --disable-pip-version-check --force-reinstall --no-deps "$wheels"/divertsim-*.whl

# The CLI the tests compare with: the caller's (the cargo test program passes its own),
# else a release build (it shares the wheel's compiled dependencies).
if [ -z "${DIVERTSIM_BIN:-}" ]; then
    cargo build --release --quiet -p divertsim
    export DIVERTSIM_BIN="$CARGO_TARGET_DIR/release/divertsim"
fi

# From the repository root: the tests name scenario files relative to it.
"$py" -m pytest crates/divertsim-py/tests -q -p no:cacheprovider
echo "python-tests: $((SECONDS - start)) s"
