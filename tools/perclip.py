#!/usr/bin/env python3
"""Per-clip encoder time against ACL's compressor, alternating rounds (issue 29, goal 1;
docs/performance.md, sessions 16 to 18).

perclip.py ROUNDS OUT.md FILE...   (corpus-relative paths, or absolute ones)

sinew: crates/pipeline's compress_time example at 0.001 @ 0.1, default effort, in a pool of 2 threads
(the machine's cores) and of 1, one run per fresh process, the encoder timed on the pool thread that
runs it (SINEW_TIME_HANDOFF=1: with the hand-off to the pool and back, as until session 19); ACL 2.1's acl_compressor on
gltf2acl.py's clip at the clip's own nominal rate (`sinew inspect` sample_rate), its reported
compression_time. Medians of ROUNDS rounds, each round: sinew 2 threads, sinew 1 thread, ACL, for
every file in turn. Build first: `cargo build --release -p sinew-cli`, then `cargo build --release -p
sinew-pipeline --example compress_time` (with --example cargo builds only the examples). PEERS_DIR: where ../shared/peers/install.sh built the peers (default /work/peers);
SINEW_CORPUS: the corpus (default ../shared/corpus)."""
import json, os, re, statistics, subprocess, sys, tempfile
MAIN = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
C = os.environ.get("SINEW_CORPUS", os.path.join(MAIN, "..", "shared", "corpus"))
PEERS = os.environ.get("PEERS_DIR", "/work/peers")
BIN = os.environ.get("BIN", f"{MAIN}/target/release/examples/compress_time")
SINEW = f"{MAIN}/target/release/sinew"
ACL = f"{PEERS}/acl-build/tools/acl_compressor/main_generic/acl_compressor"
PY = f"{PEERS}/venv/bin/python"; G2A = os.path.join(MAIN, "..", "shared", "peers", "gltf2acl.py")
rounds, out = int(sys.argv[1]), sys.argv[2]
tmp = tempfile.mkdtemp()
def sinew_run(f, threads):
    env = dict(os.environ, SINEW_THREADS=str(threads), SINEW_CORPUS=C)
    r = subprocess.run([BIN, "1", f], capture_output=True, text=True, env=env, cwd=MAIN)
    rows = {}
    for l in r.stdout.splitlines():
        if not l.startswith("| ") or l.startswith("| file"): continue
        c = [x.strip() for x in l.strip().strip("|").split("|")]
        rows[c[1]] = (float(c[4]), int(c[3]), float(c[6]), c[2])
    return rows
def acl_run(path):
    s = os.path.join(tmp, "s.sjson")
    subprocess.run([ACL, f"-acl={path}", f"-stats={s}"], capture_output=True)
    t = open(s).read()
    g = lambda k: float(re.search(k + r"\s*=\s*([-0-9.e]+)", t).group(1))
    return g("compression_time") * 1000, int(g("compressed_size")), g("max_error")
plan = []
for f in sys.argv[3:]:
    src = f if os.path.isabs(f) else f"{C}/{f}"
    info = json.loads(subprocess.run([SINEW, "inspect", src, "--json"], capture_output=True, text=True).stdout)
    glb = src if f.endswith((".glb", ".gltf")) else os.path.join(tmp, os.path.basename(f) + ".glb")
    if glb != src:
        subprocess.run([SINEW, "export", src, "-o", glb, "--lod", "none"], capture_output=True)
    acl = {}
    for clip in info.get("clips", []):
        d = os.path.join(tmp, re.sub(r"\W", "_", f + clip["name"]))
        subprocess.run([PY, G2A, glb, d, "--rate", repr(clip["sample_rate"])], capture_output=True)
        safe = "".join(ch if ch.isalnum() else "_" for ch in clip["name"])
        files = [x for x in os.listdir(d) if x.endswith(".acl.sjson")] if os.path.isdir(d) else []
        match = [x for x in files if x.endswith("_" + safe + ".acl.sjson")]
        if match: acl[clip["name"]] = (os.path.join(d, match[0]), clip["sample_rate"])
    plan.append((f, acl))
res = {}
for r in range(rounds):
    for f, acl in plan:
        for threads in (2, 1):
            for clip, v in sinew_run(f, threads).items():
                res.setdefault((f, clip), {}).setdefault(f"s{threads}", []).append(v)
        for clip, (p, rate) in acl.items():
            res.setdefault((f, clip), {}).setdefault("acl", []).append(acl_run(p) + (rate,))
with open(out, "w") as o:
    o.write("| file | clip | joints x keys | sinew 2 threads ms | sinew 1 thread ms | ACL ms (rate) | 2 threads / ACL | sinew B | ACL B | sinew max error | ACL max error |\n|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n")
    for (f, clip), d in res.items():
        s2, s1 = d.get("s2", []), d.get("s1", [])
        if not s2: continue
        m2 = statistics.median(x[0] for x in s2); m1 = statistics.median(x[0] for x in s1)
        a = d.get("acl")
        if a:
            ma = statistics.median(x[0] for x in a)
            o.write(f"| {f} | {clip} | {s2[0][3]} | {m2:.2f} | {m1:.2f} | {ma:.2f} ({a[0][3]:g} Hz) | {m2/ma:.2f} | {s2[0][1]:,} | {a[0][1]:,} | {s2[0][2]:.6f} | {a[0][2]:.6f} |\n")
        else:
            o.write(f"| {f} | {clip} | {s2[0][3]} | {m2:.2f} | {m1:.2f} | — | | {s2[0][1]:,} | | {s2[0][2]:.6f} | |\n")
print("wrote", out)
