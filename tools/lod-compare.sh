#!/usr/bin/env bash
# Compares sinew's LODs with gltfpack's on the same glTF files at the same targets (issue 6).
# Installs gltfpack from npm into a temporary folder, simplifies each file to 50% and 25% of its
# triangles (each from the source, no quantisation), then runs examples/lod_compare.rs, which imports
# the original and gltfpack's outputs with sinew_import and prints triangles reached, Hausdorff
# distance, posed Hausdorff and sinew's time. gltfpack's time is printed here (whole process).
#
# usage: tools/lod-compare.sh [FILE.glb ...]   (default: CesiumMan.glb and Fox.glb of the corpus)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
corpus="${SINEW_CORPUS:-$root/../shared/corpus}"
if [ "$#" -eq 0 ]; then
  set -- "$corpus/gltf/CesiumMan.glb" "$corpus/gltf/Fox.glb"
fi
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
npm install --silent --prefix "$tmp" gltfpack@1.3.0 >/dev/null
gltfpack="$tmp/node_modules/.bin/gltfpack"
cargo build --quiet --release -p sinew-pipeline --example lod_compare
for input in "$@"; do
  base="$(basename "${input%.*}")"
  outs=()
  for ratio in 0.5 0.25; do
    out="$tmp/${base}_gltfpack_${ratio}.glb"
    start=$(date +%s%N)
    "$gltfpack" -i "$input" -o "$out" -si "$ratio" -noq >/dev/null
    end=$(date +%s%N)
    echo "gltfpack -si $ratio $base: $(( (end - start) / 1000000 )) ms (whole process)"
    outs+=("$out")
  done
  "$root/target/release/examples/lod_compare" "$input" "${outs[@]}"
done
