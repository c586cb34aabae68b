#!/usr/bin/env bash
# Error per byte: a pgvol .pgv file (default settings) against a dense float32 trilinear grid of
# the same number of bytes and against OpenVDB's .vdb file at the same grid spacing (meshToVolume
# +-3 voxels, volumeToMesh; needs Debian's python3-openvdb for /usr/bin/python3), all turned into
# meshes and compared with the input.
# Usage: bash tools/bench/bytes_vs_dense.sh [MESH ...]   (names in ../shared/meshes, default three)
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$ROOT"
MESHES="${PGVOL_SHARED_MESHES:-$ROOT/../shared/meshes}"
P="${PGVOL_BIN:-$ROOT/target/release/pgvol}"
[[ -x "$P" ]] || cargo build --release
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
chamfer() { "$P" compare "$1" "$2" --samples 200000 --json | python3 -c "import json,sys; print('%.5f' % json.load(sys.stdin)['chamfer_l1_pct'])"; }
VDB_PY="${PGVOL_BENCH_SYSTEM_PYTHON:-/usr/bin/python3}"
echo "| mesh | res | .pgv bytes | Chamfer-L1 % | dense n (same bytes) | dense Chamfer-L1 % | ratio to dense | .vdb bytes (half) | .vdb Chamfer-L1 % | ratio to .vdb |"
echo "|---|---|---|---|---|---|---|---|---|---|"
if [[ $# -eq 0 ]]; then set -- stanford-bunny fandisk spot; fi
for m in "$@"; do
  for r in 64 128; do
    "$P" encode "$MESHES/$m.obj" -o "$work/a.pgv" --res "$r" -q
    "$P" decode "$work/a.pgv" -o "$work/a.glb" -q
    bytes=$(stat -c %s "$work/a.pgv")
    ours=$(chamfer "$work/a.glb" "$MESHES/$m.obj")
    # A dense float32 grid of n^3 values takes 4 n^3 bytes.
    n=$(python3 -c "print(round(($bytes / 4) ** (1 / 3)))")
    "$P" remesh "$MESHES/$m.obj" -o "$work/t.glb" --res "$n" --field decoded --basis trilinear -q
    dense=$(chamfer "$work/t.glb" "$MESHES/$m.obj")
    vdb="n/a"; vdbc="n/a"; vdbr="n/a"
    if info=$("$VDB_PY" tools/bench/vdb_file.py "$MESHES/$m.obj" "$r" "$work/v" 2>/dev/null); then
      vdb=$(python3 -c "import json,sys; d=json.loads(sys.argv[1]); print('%d (%d)' % (d['bytes'], d['bytes_half']))" "$info")
      vdbc=$(chamfer "$work/v.obj" "$MESHES/$m.obj")
      vdbr=$(python3 -c "print('%.2f' % ($ours / $vdbc))")
    fi
    echo "| $m | $r | $bytes | $ours | $n | $dense | $(python3 -c "print('%.2f' % ($ours / $dense))") | $vdb | $vdbc | $vdbr |"
  done
done
