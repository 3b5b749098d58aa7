#!/bin/bash
# Whole-process wall times against the same-work peers, alternating rounds (issue 29, goals 2 and 3;
# docs/performance.md): per file, gltf2ozz, native gltfpack (`-noq`, `-si 0.5`, `-si 0.25`, each
# `-noq`) and sinew (`--lod none --effort fast`, `--lod none`, `--lod none --no-compress`, the
# default), medians of tools/alternate.py.
#
# usage: [ROUNDS=7] [PEERS_DIR=/work/peers] tools/wall.sh FILE.glb...
#   (build sinew first: cargo build --release -p sinew-cli; PEERS_DIR as ../shared/peers/install.sh)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
peers="${PEERS_DIR:-/work/peers}"
S="$root/target/release/sinew"
O="$peers/ozz-build/src/animation/offline/gltf/gltf2ozz"
GP="$peers/gltfpack-build/gltfpack"
for f in "$@"; do
  f=$(readlink -f "$f"); d=$(mktemp -d); echo "== $(basename "$f")"
  # gltf2ozz writes its files where it runs.
  cd "$d"
  python3 "$root/tools/alternate.py" "${ROUNDS:-7}" ozz "$O --file=$f" noq "$GP -i $f -o $d/a.glb -noq" \
    si05 "$GP -i $f -o $d/b.glb -si 0.5 -noq" si025 "$GP -i $f -o $d/c.glb -si 0.25 -noq" \
    fast "$S convert $f -o $d/f.sinew --lod none --effort fast -q" lodnone "$S convert $f -o $d/l.sinew --lod none -q" \
    bare "$S convert $f -o $d/b.sinew --lod none --no-compress -q" default "$S convert $f -o $d/d.sinew -q"
  cd "$root"; rm -rf "$d"
done
