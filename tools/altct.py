#!/usr/bin/env python3
"""Per-clip encoder time of two builds, alternating (issue 29; docs/performance.md, session 18).

altct.py ROUNDS BIN_A BIN_B FILE...   (FILE: corpus-relative paths)

BIN_A and BIN_B are builds of crates/pipeline's compress_time example (0.001 @ 0.1). Each round runs
A then B on every file, one run per fresh process, in a pool of SINEW_THREADS threads (default 2).
Prints per clip the median of each, B / A, and both record sizes (which should be equal when a
change keeps the output)."""
import os, statistics, subprocess, sys

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
rounds, a, b, files = int(sys.argv[1]), sys.argv[2], sys.argv[3], sys.argv[4:]
env = dict(os.environ)
env.setdefault("SINEW_THREADS", "2")
env.setdefault("SINEW_CORPUS", os.path.join(root, "..", "shared", "corpus"))
res = {}
for _ in range(rounds):
    for f in files:
        for tag, binary in (("A", a), ("B", b)):
            out = subprocess.run([binary, "1", f], capture_output=True, text=True, env=env).stdout
            for line in out.splitlines():
                if not line.startswith("| ") or line.startswith("| file"):
                    continue
                c = [x.strip() for x in line.strip().strip("|").split("|")]
                res.setdefault((f, c[1]), {}).setdefault(tag, []).append((float(c[4]), c[3]))
for (f, clip), d in res.items():
    ma = statistics.median(x[0] for x in d["A"])
    mb = statistics.median(x[0] for x in d["B"])
    print(f"{f} {clip}: A {ma:.2f} B {mb:.2f} ms, B/A {mb / ma:.3f}, bytes {d['A'][0][1]} {d['B'][0][1]}")
