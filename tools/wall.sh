#!/bin/bash
# Whole-process wall times against the same-work peers, alternating rounds (issue 29, goals 2 and 3;
# docs/performance.md): per file, gltf2ozz, native gltfpack (`-noq`, `-si 0.5`, `-si 0.25`, each
# `-noq`) and sinew (`--lod none --effort fast`, `--lod none`, `--lod none --no-compress`, the
# default), medians of tools/alternate.py.
#
# Every binary runs from an installed copy (`install -m755` into a temporary folder), as a user's
# `cargo install` or package runs it: on this machine the linker-written target/release/sinew cost
# 0.8-1.0 ms more per process than any copy of it (the same bytes; `cp`, `install`, Python's
# copyfile alike), the peers' build outputs no more than their copies (docs/performance.md,
# session 36). `WALL_IN_PLACE=1` runs them where they were built, as before.
#
# usage: [ROUNDS=7] [PEERS_DIR=/work/peers] tools/wall.sh FILE.glb...
#   (build sinew first: cargo build --release -p sinew-cli; PEERS_DIR as ../shared/peers/install.sh)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
peers="${PEERS_DIR:-/work/peers}"
S="$root/target/release/sinew"
O="$peers/ozz-build/src/animation/offline/gltf/gltf2ozz"
GP="$peers/gltfpack-build/gltfpack"
if [ -z "${WALL_IN_PLACE:-}" ]; then
  bin=$(mktemp -d)
  trap 'rm -rf "$bin"' EXIT
  install -m755 "$S" "$bin/sinew"; install -m755 "$O" "$bin/gltf2ozz"; install -m755 "$GP" "$bin/gltfpack"
  S="$bin/sinew"; O="$bin/gltf2ozz"; GP="$bin/gltfpack"
fi
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
