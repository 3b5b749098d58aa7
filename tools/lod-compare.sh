#!/usr/bin/env bash
# sinew's LODs against native gltfpack at equal triangle counts, per mesh, at rest and posed
# (issue 30; docs/lod.md, "Against gltfpack at equal triangle counts").
#
# Every input that is not glTF is exported first (`sinew export FILE -o FILE.glb`): that file is
# the reference for both tools. crates/pipeline/examples/lod_peers.rs then runs gltfpack (`-si 0.5`
# and `-si 0.25`, each with and without `-sa`, always `-kn -noq`), builds sinew's default chain and
# its chain at gltfpack's counts, and prints one JSON line per mesh and level; tools/lod-table.py
# turns them into the tables of docs/lod.md.
#
# usage: GLTFPACK=/path/to/gltfpack [PLAIN=1] tools/lod-compare.sh OUT.jsonl [FILE ...]
#   (PLAIN=1: sinew's chains with the plain builds of `convert --effort max`; PLAIN_WORK=N: with
#   them on the meshes whose plain work is at most N instead of the default bound; POSE_AT="F ...":
#   the clip times measured posed instead of 0.125 0.25 0.5 0.75 of the first clip, C.F for clip C)
#   (default files: the corpus meshes and fixtures of docs/lod.md; GLTFPACK defaults to the
#   peers' build, /work/peers/gltfpack-build/gltfpack)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
corpus="${SINEW_CORPUS:-$root/../shared/corpus}"
gltfpack="${GLTFPACK:-/work/peers/gltfpack-build/gltfpack}"
out="${1:?usage: tools/lod-compare.sh OUT.jsonl [FILE ...]}"
shift
if [ "$#" -eq 0 ]; then
  set -- "$root/fixtures/thin.gltf" "$root/fixtures/parts.gltf" "$root/fixtures/biped.gltf" \
    "$corpus/gltf/CesiumMan.glb" "$corpus/gltf/Fox.glb" "$corpus/gltf/RiggedFigure.glb" \
    "$corpus/gltf/RiggedSimple.glb" "$corpus/ms3d/ninja.ms3d" "$corpus/ms3d/zombie.ms3d" \
    "$corpus/ms3d/zombie02.ms3d" "$corpus/ms3d/jeep1.ms3d" "$corpus/ms3d/Wuson.ms3d" \
    "$corpus/ms3d/twospheres_withmats.ms3d" "$corpus/ms3d/animated_cylinder.ms3d" \
    "$corpus/ms3d/cross.ms3d" "$corpus/obj/spot.obj" "$corpus/obj/spider.obj" \
    "$corpus/obj/regr01.obj" "$corpus/obj/cornell_box.obj" "$corpus/mdl/man.mdl" \
    "$corpus/mdl/chrome_sphere.mdl" "$corpus/smd/holy_grailref.smd" "$corpus/smd/WusonSMD.smd"
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# Two builds: with --example, cargo builds only the examples, not sinew-cli's binary.
cargo build --quiet --release -p sinew-cli
cargo build --quiet --release -p sinew-pipeline --example lod_peers
inputs=()
for input in "$@"; do
  case "$input" in
    *.glb|*.gltf) inputs+=("$input") ;;
    *)
      b="$(basename "$input")"
      glb="$tmp/${b%.*}_${b##*.}.glb"
      "$root/target/release/sinew" -q export "$input" -o "$glb"
      inputs+=("$glb") ;;
  esac
done
plain=()
if [ -n "${PLAIN:-}" ]; then plain=(--plain); fi
if [ -n "${PLAIN_WORK:-}" ]; then plain+=(--plain-work "$PLAIN_WORK"); fi
poses=()
for at in ${POSE_AT:-0.125 0.25 0.5 0.75}; do poses+=(--pose-at "$at"); done
"$root/target/release/examples/lod_peers" --gltfpack "$gltfpack" "${plain[@]}" \
  "${poses[@]}" "${inputs[@]}" > "$out"
echo "wrote $out ($(wc -l < "$out") rows)"
