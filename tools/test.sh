#!/usr/bin/env bash
# The project's single test command: checks formatting and lints, builds pgvol, sets up the
# Python and Node helpers, installs the Python package (crates/pgvol-py) into the venv, runs the
# Rust tests (with the library's doctests), the Python package's tests and the end-to-end checks
# in tools/checks.
# Usage: bash tools/test.sh   (from any directory; needs only the package registries)
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"

section() { printf '\n==> %s\n' "$*"; }

hash_of() { sha256sum "$@" | sha256sum | cut -d' ' -f1; }

section "cargo fmt --check"
cargo fmt --all -- --check

section "cargo clippy (warnings are errors)"
cargo clippy --workspace --all-targets -- -D warnings

section "dependency boundaries"
# Reading a .pgv file must not pull in the mesh file formats or the BVH.
if cargo tree -p pgvol-format -e normal --prefix none | grep -E '^(gltf|tobj|pgvol-sdf) '; then
    echo "pgvol-format depends on a mesh file format or the BVH (above)"; exit 1
fi
echo "pgvol-format is free of gltf, tobj and the BVH (pgvol-sdf)"

section "import cycles"
python3 tools/check_cycles.py

section "cargo build --release"
cargo build --release

section "system tools (apt: OpenVDB, Blender, PrusaSlicer)"
# The interop checks read pgvol's files back with other tools: OpenVDB (pyopenvdb under the
# system Python, vdb_print), Blender's volume import and PrusaSlicer's 3MF export. Installed only
# where dpkg does not list them.
apt_missing=()
for pkg in python3-openvdb libopenvdb-tools blender prusa-slicer; do
    dpkg -s "$pkg" >/dev/null 2>&1 || apt_missing+=("$pkg")
done
if [[ ${#apt_missing[@]} -gt 0 ]]; then
    sudo_cmd=()
    [[ "$(id -u)" != 0 ]] && sudo_cmd=(sudo)
    "${sudo_cmd[@]}" apt-get update -q
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q \
        --no-install-recommends "${apt_missing[@]}"
else
    echo "python3-openvdb, libopenvdb-tools, blender and prusa-slicer are installed"
fi

section "chromium (apt: the checks of pgvol view)"
# tools/checks/test_view.py opens the viewer's pages in headless Chromium.
if ! dpkg -s chromium >/dev/null 2>&1; then
    sudo_cmd=()
    [[ "$(id -u)" != 0 ]] && sudo_cmd=(sudo)
    "${sudo_cmd[@]}" apt-get update -q
    DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends chromium
else
    echo "chromium is installed"
fi

section "python environment (.venv)"
PY="${PYTHON:-python3}"
if [[ ! -x .venv/bin/python ]]; then
    "$PY" -m venv .venv
fi
req_hash="$(hash_of tools/requirements.txt)"
stamp=.venv/.pgvol-requirements.sha256
if [[ ! -f "$stamp" || "$(cat "$stamp")" != "$req_hash" ]]; then
    .venv/bin/python -m pip install -q --disable-pip-version-check -r tools/requirements.txt
    echo "$req_hash" > "$stamp"
else
    echo "requirements unchanged; skipping pip install"
fi

section "node helpers (tools/node_modules)"
lock_hash="$(hash_of tools/package.json tools/package-lock.json)"
nstamp=tools/node_modules/.pgvol-lock.sha256
if [[ ! -f "$nstamp" || "$(cat "$nstamp")" != "$lock_hash" ]]; then
    npm ci --prefix tools --no-audit --no-fund --loglevel=error
    echo "$lock_hash" > "$nstamp"
else
    echo "package-lock unchanged; skipping npm ci"
fi

# Every suite runs even if one before it fails, so one CI log shows every failure.
failed=()

section "python package (pip install ./crates/pgvol-py)"
# pip builds the package in place with maturin, in release, into the repository's target/
# (or CARGO_TARGET_DIR): after the first build only what changed is compiled again.
py_start=$SECONDS
if CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}" \
    .venv/bin/python -m pip install -q --disable-pip-version-check ./crates/pgvol-py; then
    py_installed=1
else
    py_installed=0
    failed+=("pip install ./crates/pgvol-py")
fi
echo "built and installed in $((SECONDS - py_start)) s"

section "cargo test --release --workspace"
# The bindings have no Rust tests (their suite is pytest's, below). Left in, pyo3's macros
# would turn on more of syn's features, and every crate of the test build would be compiled again
# with them instead of reusing the builds of earlier runs.
cargo test --release --workspace --exclude pgvol-py || failed+=("cargo test")

section "python package tests (pytest crates/pgvol-py/tests)"
if [[ $py_installed == 1 ]]; then
    .venv/bin/python -m pytest -q -p no:cacheprovider crates/pgvol-py/tests \
        || failed+=("pytest crates/pgvol-py/tests")
fi

section "python type stubs (mypy.stubtest pgvol)"
# The stubs (_pgvol.pyi) and the package's Python modules against the installed extension:
# every name, signature and default the module has at runtime, and no more. Needs no allowlist.
if [[ $py_installed == 1 ]]; then
    .venv/bin/python -m mypy.stubtest pgvol || failed+=("mypy.stubtest pgvol")
fi

section "end-to-end checks (pytest tools/checks)"
.venv/bin/python -m pytest -q -p no:cacheprovider tools/checks || failed+=("pytest tools/checks")

if [[ ${#failed[@]} -gt 0 ]]; then
    section "FAILED: ${failed[*]}"
    exit 1
fi
section "all tests passed"
