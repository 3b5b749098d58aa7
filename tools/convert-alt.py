#!/usr/bin/env python3
"""Alternating whole-process timings of two `sinew` binaries on the animated corpus files.

tools/convert-alt.py RUNS OUT.tsv BIN_A BIN_B [EXTRA_ARGS...]

For each file: one warm-up run of each, then RUNS rounds of `A convert FILE -o TMP -q --no-textures EXTRA`
followed by the same with B (a quarter of RUNS, at least 3, for the two long BVH captures); prints and
writes the median and fastest wall time of each and the ratio of the medians. FILES (space-separated,
relative to the corpus) replaces the file list; the corpus is SINEW_CORPUS or ../shared/corpus.
Used for the "Convert speed" tables of docs/performance.md."""
import os, statistics, subprocess, sys, tempfile, time
OUT_SINEW = os.path.join(tempfile.mkdtemp(), "out.sinew")
runs, out, a, b = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4]
extra = sys.argv[5:]
C = os.environ.get("SINEW_CORPUS") or os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "corpus")
files = ["gltf/CesiumMan.glb", "gltf/Fox.glb", "gltf/RiggedFigure.glb", "gltf/RiggedSimple.glb", "gltf/SimpleSkin.gltf",
         "gltf/magnum/animation.glb", "ms3d/ninja.ms3d", "ms3d/zombie.ms3d", "ms3d/zombie02.ms3d", "ms3d/animated_cylinder.ms3d",
         "ms3d/cross.ms3d", "bvh/cmu_walk_crlf.bvh", "bvh/cmu_01_01.bvh", "bvh/Boxing_Toes.bvh", "bvh/sinusoidal_xyz.bvh",
         "bvh/test_simple.bvh", "bvh/pfnn_hierarchy_crlf.bvh", "mdl/man.mdl", "mdl/chrome_sphere.mdl"]
if os.environ.get("FILES"): files = os.environ["FILES"].split()
def one(binary, f):
    t = time.perf_counter()
    subprocess.run([binary, "convert", f"{C}/{f}", "-o", OUT_SINEW, "-q", "--no-textures"] + extra, check=True)
    return time.perf_counter() - t
rows = []
for f in files:
    n = runs if not ("cmu_01" in f or "Boxing" in f) else max(3, runs // 4)
    ta, tb = [], []
    one(a, f); one(b, f)
    for _ in range(n):
        ta.append(one(a, f)); tb.append(one(b, f))
    ma, mb = statistics.median(ta), statistics.median(tb)
    rows.append((f, n, ma, min(ta), mb, min(tb), ma / mb))
    print(f"{f:30} n={n:2}  A {ma*1000:8.1f} ms (min {min(ta)*1000:7.1f})  B {mb*1000:8.1f} ms (min {min(tb)*1000:7.1f})  A/B {ma/mb:5.2f}", flush=True)
with open(out, "w") as fo:
    fo.write("file\truns\tA_median_ms\tA_min_ms\tB_median_ms\tB_min_ms\tA_over_B\n")
    for r in rows:
        fo.write(f"{r[0]}\t{r[1]}\t{r[2]*1000:.1f}\t{r[3]*1000:.1f}\t{r[4]*1000:.1f}\t{r[5]*1000:.1f}\t{r[6]:.2f}\n")
