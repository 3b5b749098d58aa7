#!/usr/bin/env python3
"""Tables of docs/lod.md from tools/lod-compare.sh's JSON lines.

usage: tools/lod-table.py RESULTS.jsonl [--mesh-rows]

Prints, per file and mesh (meshes of at least 100 triangles with --mesh-rows, else one summary per
file): sinew's default LODs (triangles, rest / worst posed distance, % of the mesh diagonal), and
for each gltfpack setting and level gltfpack's triangles and distances next to sinew's chain at
the same counts; then the counts of comparisons where sinew is farther (by more than 0.001 points)
at rest and at any pose. Comparisons where gltfpack kept every triangle of a mesh are left out.
"""
import json
import sys

TOL = 1e-3


def worst(rest, posed):
    vals = [v for v in [rest] + list(posed) if v is not None]
    return max(vals) if vals else None


def f(v):
    return "-" if v is None else f"{v:.3f}"


def main():
    rows = [json.loads(line) for line in open(sys.argv[1])]
    mesh_rows = "--mesh-rows" in sys.argv
    sinew = {}
    peers = {}
    for r in rows:
        key = (r["file"], r["mesh"])
        if r["tool"] == "sinew":
            sinew.setdefault(key, {})[r["level"]] = r
        else:
            peers.setdefault(key, {}).setdefault(r["setting"], {})[r["level"]] = r
    print("| file / mesh | LOD 0 | sinew LOD 1 | sinew LOD 2 | gltfpack -si (L1; L2) | sinew at those counts | gltfpack -si -sa (L1; L2) | sinew at those counts |")
    print("|---|---:|---|---|---|---|---|---|")
    totals = [0, 0, 0]
    for key in sinew:
        file, mesh = key
        base = next(iter(sinew[key].values()))["base"]
        if mesh_rows and base < 100:
            continue

        def lod(level):
            r = sinew[key].get(level)
            if r is None:
                return "not built"
            return f"{r['triangles']}: {f(r['rest'])} / {f(worst(None, r['posed']))}"

        cells = []
        for setting in ("si", "si-sa"):
            g = peers.get(key, {}).get(setting, {})
            gl, sl = [], []
            for level in (1, 2):
                r = g.get(level)
                if r is None:
                    gl.append("-")
                    sl.append("-")
                    continue
                gl.append(f"{r['triangles']}: {f(r['rest'])} / {f(worst(None, r['posed']))}")
                sl.append(f"{r['matched_triangles']}: {f(r['matched_rest'])} / {f(worst(None, r['matched_posed']))}")
                if r["triangles"] < r["base"]:
                    totals[0] += 1
                    if r["matched_rest"] is not None and r["rest"] is not None and r["matched_rest"] > r["rest"] + TOL:
                        totals[1] += 1
                    if any(m is not None and p is not None and m > p + TOL for m, p in zip(r["matched_posed"], r["posed"])):
                        totals[2] += 1
            cells += ["; ".join(gl), "; ".join(sl)]
        name = file if mesh == file.rsplit(".", 1)[0] else f"{file} / {mesh}"
        print(f"| {name} | {base} | {lod(1)} | {lod(2)} | " + " | ".join(cells) + " |")
    print()
    print(f"comparisons (gltfpack simplified the mesh): {totals[0]}; sinew farther at rest: {totals[1]}; at some pose: {totals[2]}")


if __name__ == "__main__":
    main()
