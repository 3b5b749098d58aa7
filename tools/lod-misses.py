#!/usr/bin/env python3
"""Where sinew's LODs are farther than gltfpack's at equal triangle counts, from the JSON lines of
tools/lod-compare.sh (issue 30; docs/lod.md, "Against gltfpack at equal triangle counts").

lod-misses.py OUT.jsonl [...]

Per file of rows: the comparisons (gltfpack's level against sinew's chain built at the count it
reached) farther at rest, farther at some pose, how many poses farther and closer in all, and per
comparison farther at some pose its worst ratio (sinew's distance over gltfpack's); then each
comparison farther by more than 1e-3 % of the diagonal, at rest or at a pose."""
import json, sys

for fn in sys.argv[1:]:
    rows = [json.loads(l) for l in open(fn)]
    rest = posed = farther = closer = total = 0
    worst, lines = [], []
    for r in rows:
        if r["tool"] != "gltfpack" or "matched_rest" not in r or r["triangles"] >= r["base"]:
            continue
        total += 1
        pairs = [(a, b) for a, b in zip(r["matched_posed"] or [], r["posed"] or [])
                 if a is not None and b is not None]
        bad = [(k, a, b) for k, (a, b) in enumerate(pairs) if a > b + 1e-3]
        farther += len(bad)
        closer += sum(1 for a, b in pairs if a < b - 1e-3)
        at_rest = r["matched_rest"] > r["rest"] + 1e-3
        rest += at_rest
        if bad:
            posed += 1
            worst.append(max(a / b if b > 0 else float("inf") for _, a, b in bad))
        if at_rest or bad:
            pose = ""
            if bad:
                k, a, b = max(bad, key=lambda x: x[1] - x[2])
                pose = f", pose {k} {a:.3f} vs {b:.3f} ({len(bad)} of {len(pairs)} poses farther)"
            lines.append(f"  {r['file']} {r['mesh']} {r['setting']} L{r['level']}: gltfpack "
                         f"{r['triangles']}, sinew {r['matched_triangles']}; rest "
                         f"{r['matched_rest']:.3f} vs {r['rest']:.3f}{pose}")
    print(f"{fn}: {total} comparisons, farther at rest {rest}, at some pose {posed}; poses "
          f"farther {farther}, closer {closer}")
    if worst:
        print("  worst pose ratio per comparison farther posed:",
              ", ".join(f"{w:.2f}" for w in sorted(worst)))
    print("\n".join(lines))
