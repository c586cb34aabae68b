#!/usr/bin/env bash
# Benchmarks pgvol against peer libraries.
# Usage: bash tools/bench/run.sh [sdf|remesh|all] [--big]
#        bash tools/bench/run.sh points [--quick]   (surfaces through points and contours)
#        bash tools/bench/run.sh scale [bench_scale.py options]   (encode / decode against OpenVDB)
#        bash tools/bench/run.sh sharp [bench_sharp.py options]   (sharp edges through the file)
# Sets up tools/.venv-bench (peers that fail to install are reported as n/a),
# installs Debian's python3-openvdb, libeigen3-dev and libusb-1.0-0 (which Open3D loads), and
# what the C++ OpenVDB driver of bench_scale.py builds with (g++, make, libopenvdb-dev,
# libboost-dev) and time when missing (needs root),
# builds pgvol (cargo build --release), and prints markdown tables.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"

what="all"
if [[ $# -gt 0 && "$1" != -* ]]; then
    what="$1"
    shift
fi
case "$what" in sdf|remesh|all|points|scale|sharp) ;; *) echo "usage: $0 [sdf|remesh|all|points|scale|sharp] [--big]" >&2; exit 2 ;; esac

section() { printf '\n==> %s\n' "$*" >&2; }

section "system packages"
missing=()
for pkg in python3-openvdb libeigen3-dev libusb-1.0-0 g++ make libopenvdb-dev libboost-dev time; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if [[ ${#missing[@]} -gt 0 ]]; then
    if [[ "$(id -u)" -eq 0 ]]; then
        { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null; } \
            || echo "warning: could not install ${missing[*]}; the peers needing them will show n/a" >&2
    else
        echo "warning: not root; install ${missing[*]} by hand for the OpenVDB / pysdf peers" >&2
    fi
else
    echo "system packages present" >&2
fi
if [[ -d /usr/include/eigen3 ]]; then
    export CPATH="/usr/include/eigen3${CPATH:+:$CPATH}"
fi

section "python environment (tools/.venv-bench)"
VENV=tools/.venv-bench
REQ=tools/bench/requirements.txt
if [[ ! -x "$VENV/bin/python" ]]; then
    python3 -m venv "$VENV"
fi
req_hash="$(sha256sum "$REQ" | cut -d' ' -f1)"
stamp="$VENV/.requirements.sha256"
if [[ ! -f "$stamp" || "$(cat "$stamp")" != "$req_hash" ]]; then
    rm -rf "$VENV/install-failures"
    mkdir -p "$VENV/install-failures"
    if ! "$VENV/bin/python" -m pip install -q --disable-pip-version-check -r "$REQ" \
            >"$VENV/install-failures/all.log" 2>&1; then
        echo "installing everything at once failed; installing one package at a time" >&2
        while IFS= read -r line; do
            line="${line%%#*}"
            line="$(echo "$line" | xargs)"
            [[ -z "$line" ]] && continue
            name="${line%%[=<>!;~ ]*}"
            if ! "$VENV/bin/python" -m pip install -q --disable-pip-version-check "$line" \
                    >"$VENV/install-failures/$name.log" 2>&1; then
                echo "warning: $line did not install (see $VENV/install-failures/$name.log)" >&2
            else
                rm -f "$VENV/install-failures/$name.log"
            fi
        done <"$REQ"
    fi
    rm -f "$VENV/install-failures/all.log"
    # Record success only when everything installed, so failed peers are retried next time.
    if [[ -z "$(ls -A "$VENV/install-failures")" ]]; then
        echo "$req_hash" >"$stamp"
    fi
else
    echo "requirements unchanged; skipping pip install" >&2
fi

section "pgvol binary"
# PGVOL_BIN=path benchmarks another build; PGVOL_BENCH_NO_BUILD=1 uses target/release/pgvol as it is.
if [[ -z "${PGVOL_BIN:-}" && "${PGVOL_BENCH_NO_BUILD:-0}" != 1 ]]; then
    if ! cargo build --release >&2; then
        if [[ -x target/release/pgvol ]]; then
            echo "warning: cargo build failed; benchmarking the existing target/release/pgvol" >&2
        else
            echo "error: cargo build failed and there is no pgvol binary" >&2
            exit 1
        fi
    fi
fi

if [[ "$what" == sdf || "$what" == all ]]; then
    section "SDF benchmark"
    "$VENV/bin/python" tools/bench/bench_sdf.py "$@"
fi
if [[ "$what" == remesh || "$what" == all ]]; then
    section "remesh benchmark"
    "$VENV/bin/python" tools/bench/bench_remesh.py "$@"
fi
if [[ "$what" == points ]]; then
    section "points and contours benchmark"
    "$VENV/bin/python" tools/bench/bench_points.py "$@"
fi
if [[ "$what" == sharp ]]; then
    section "sharp edges through the file"
    "$VENV/bin/python" tools/bench/bench_sharp.py "$@"
fi
if [[ "$what" == scale ]]; then
    section "encode / decode scaling against OpenVDB"
    "$VENV/bin/python" tools/bench/bench_scale.py "$@"
fi
