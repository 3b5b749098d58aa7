#!/bin/bash
# Whether two builds of `sinew` give the same outputs (docs/performance.md, session 18): every corpus
# model converted by both at four settings (the default, `--tolerance 0.001 --error-distance 0.1`,
# `--effort fast`, `--effort max`), the `.sinew` bytes and the JSON reports compared.
#
# usage: tools/samebytes.sh SINEW_A SINEW_B [WORKDIR]   (SINEW_CORPUS: default ../shared/corpus)
set -u
root="$(cd "$(dirname "$0")/.." && pwd)"
A=$1; B=$2; O=${3:-$(mktemp -d)}; C=${SINEW_CORPUS:-$root/../shared/corpus}
rm -rf "$O"; mkdir -p "$O/a" "$O/b"
n=0; d=0
while IFS= read -r f; do
  for s in "" "--tolerance 0.001 --error-distance 0.1" "--effort fast" "--effort max"; do
    for x in a b; do
      bin=$A; [ $x = b ] && bin=$B
      # shellcheck disable=SC2086
      (cd "$O/$x" && "$bin" -q --json convert "$f" -o out.sinew --no-textures $s > rep.json 2>err.txt; echo "rc=$?" >> rep.json)
    done
    n=$((n+1)); same=1
    cmp -s "$O/a/rep.json" "$O/b/rep.json" || same=0
    if [ -e "$O/a/out.sinew" ] || [ -e "$O/b/out.sinew" ]; then cmp -s "$O/a/out.sinew" "$O/b/out.sinew" || same=0; fi
    if [ $same = 0 ]; then d=$((d+1)); echo "DIFF $f [$s]"; fi
    rm -f "$O/a/out.sinew" "$O/b/out.sinew"
  done
done < <(find "$C" -type f \( -name '*.ms3d' -o -name '*.glb' -o -name '*.gltf' -o -name '*.obj' -o -name '*.bvh' -o -name '*.smd' -o -name '*.mdl' -o -name '*.qc' \) | grep -v -i malformed | sort)
echo "compared $n, differing $d"
[ $d = 0 ]
