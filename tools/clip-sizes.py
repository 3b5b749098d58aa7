#!/usr/bin/env python3
"""Per-clip compressed bytes and max error of every corpus file, at the default and the peers' settings.

tools/clip-sizes.py BIN OUT.tsv   (EXTRA="--effort fast" adds arguments to every run)

Runs `BIN convert FILE --json` on every non-malformed model and motion of the corpus MANIFEST (SINEW_CORPUS
or ../shared/corpus), once as is and once with `--tolerance 0.001 --error-distance 0.1`, and writes
one row per clip: file, setting, clip, compressed bytes, max error, tolerance, process seconds."""
import json, os, subprocess, sys, tempfile, time
OUT_SINEW = os.path.join(tempfile.mkdtemp(), "out.sinew")
bin_, out = sys.argv[1], sys.argv[2]
C = os.environ.get("SINEW_CORPUS") or os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "corpus")
files = []
for line in open(f"{C}/MANIFEST.tsv").read().splitlines()[1:]:
    p, fmt = line.split("\t")[:2]
    if "malformed" in p or fmt in ("mtl", "gltf-bin"): continue
    files.append(p)
rows = []
for p in files:
    for setting, extra in (("default", []), ("peers", ["--tolerance", "0.001", "--error-distance", "0.1"])):
        t = time.time()
        r = subprocess.run([bin_, "convert", f"{C}/{p}", "-o", OUT_SINEW, "--json", "-q", "--no-textures"] + extra, capture_output=True, text=True) if not os.environ.get("EXTRA") else subprocess.run([bin_, "convert", f"{C}/{p}", "-o", OUT_SINEW, "--json", "-q", "--no-textures"] + extra + os.environ["EXTRA"].split(), capture_output=True, text=True)
        dt = time.time() - t
        try:
            d = json.loads(r.stdout)
        except Exception:
            rows.append((p, setting, "-", "ERR", "", "", f"{dt:.3f}")); continue
        for f in d.get("files", []):
            for c in f.get("clips", []):
                k = c.get("compression")
                if not k: continue
                rows.append((p, setting, c["name"], str(k["compressed_bytes"]), f'{k["max_error"]:.7g}', f'{k["tolerance"]:.7g}', f"{dt:.3f}"))
with open(out, "w") as fo:
    fo.write("file\tsetting\tclip\tbytes\tmax_error\ttolerance\tprocess_s\n")
    for r in rows: fo.write("\t".join(r) + "\n")
print(len(rows), "rows")
