#!/usr/bin/env python3
"""Mutation sweep of the whole command line (docs/reliability.md): mutated copies of real files go
through `sinew inspect` and `sinew convert`, each process with a time and memory limit; anything but
exit code 0 or 2 with a one-line error (a signal, another code, a panic message, a timeout, a partial
output) is kept in OUT/failures with the command that shows it.

    tools/mutation_sweep.py [--runs N] [--seed S] [--out DIR] [--sinew target/release/sinew] FILE...

Mutations (chosen at random with the seed, so a sweep is repeatable): bit flips, boundary integers
(0, 1, 0x7F.., 0x80.., 0xFF..) written over 1/2/4 bytes, truncations, a chunk duplicated or deleted,
and for text files numbers replaced by odd ones (-0, 1e39, nan, 99999999999, -1). Companion files
(an MDL's T and 01 files, an OBJ's MTL, a glTF's .bin) are copied beside the mutated file unchanged.
"""
import argparse
import os
import random
import re
import resource
import shutil
import subprocess
import sys
import tempfile

BOUNDARY = [0, 1, 0x7F, 0x80, 0xFF, 0x7FFF, 0x8000, 0xFFFF, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF]
ODD_NUMBERS = [b"-0", b"1e39", b"nan", b"inf", b"99999999999", b"-1", b"0", b"4294967296", b"1e-45"]
TEXT_EXT = {".bvh", ".obj", ".mtl", ".smd", ".qc", ".gltf"}


def mutate(data: bytes, text: bool, rng: random.Random) -> bytes:
    b = bytearray(data)
    kinds = ["flip", "boundary", "truncate", "duplicate", "delete"] + (["number"] * 3 if text else [])
    kind = rng.choice(kinds)
    if not b:
        return bytes(b)
    if kind == "flip":
        for _ in range(rng.randint(1, 8)):
            i = rng.randrange(len(b))
            b[i] ^= 1 << rng.randrange(8)
    elif kind == "boundary":
        width = rng.choice([1, 2, 4])
        i = rng.randrange(max(1, len(b) - width))
        v = rng.choice(BOUNDARY) & ((1 << (8 * width)) - 1)
        b[i:i + width] = v.to_bytes(width, rng.choice(["little", "big"]))
    elif kind == "truncate":
        del b[rng.randrange(len(b)):]
    elif kind in ("duplicate", "delete"):
        i = rng.randrange(len(b))
        n = rng.randint(1, min(4096, len(b) - i))
        if kind == "duplicate":
            b[i:i] = b[i:i + n]
        else:
            del b[i:i + n]
    else:
        spans = [m.span() for m in re.finditer(rb"-?\d+(\.\d+)?([eE][-+]?\d+)?", bytes(b))]
        if spans:
            s, e = rng.choice(spans)
            b[s:e] = rng.choice(ODD_NUMBERS)
    return bytes(b)


def companions(path: str):
    """Files a reader may ask for beside `path`."""
    d, name = os.path.split(path)
    stem, ext = os.path.splitext(name)
    out = []
    for other in sorted(os.listdir(d or ".")):
        o_stem, o_ext = os.path.splitext(other)
        if other == name:
            continue
        if ext.lower() == ".mdl" and o_ext.lower() == ".mdl" and o_stem.lower().startswith(stem.lower()):
            out.append(os.path.join(d, other))
        elif o_ext.lower() in (".mtl", ".bin", ".png", ".smd", ".qci"):
            out.append(os.path.join(d, other))
    return out


def limit():
    resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))


def run(cmd, timeout):
    try:
        p = subprocess.run(cmd, capture_output=True, timeout=timeout, preexec_fn=limit)
        return p.returncode, p.stderr.decode("utf-8", "replace")
    except subprocess.TimeoutExpired:
        return "timeout", ""


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timeout", type=float, default=20.0)
    ap.add_argument("--out", default="target/mutation-sweep")
    ap.add_argument("--sinew", default="target/release/sinew")
    ap.add_argument("files", nargs="+")
    a = ap.parse_args()
    rng = random.Random(a.seed)
    failures_dir = os.path.join(a.out, "failures")
    os.makedirs(failures_dir, exist_ok=True)
    counts = {}
    failures = 0
    for i in range(a.runs):
        src = a.files[i % len(a.files)]
        ext = os.path.splitext(src)[1].lower()
        with open(src, "rb") as f:
            data = mutate(f.read(), ext in TEXT_EXT, rng)
        with tempfile.TemporaryDirectory(dir=a.out) as work:
            for c in companions(src):
                shutil.copy(c, work)
            target = os.path.join(work, os.path.basename(src))
            with open(target, "wb") as f:
                f.write(data)
            out = os.path.join(work, "out.sinew")
            for cmd in ([a.sinew, "inspect", target, "--json"],
                        [a.sinew, "convert", target, "-o", out, "--no-textures"]):
                code, err = run(cmd, a.timeout)
                verb = cmd[1]
                key = (ext, verb, code if code in (0, 2) else "FAIL")
                counts[key] = counts.get(key, 0) + 1
                bad = code not in (0, 2) or "panicked" in err or (code == 2 and len(err.strip().splitlines()) != 1)
                if verb == "convert" and code == 2 and os.path.exists(out):
                    bad = True
                if bad:
                    failures += 1
                    keep = os.path.join(failures_dir, f"{i:06d}_{verb}{ext}")
                    shutil.copy(target, keep)
                    print(f"FAIL {verb} {keep}: code {code}: {err.strip()[:300]}", flush=True)
    for key in sorted(counts, key=str):
        print(f"{key[0]:6} {key[1]:8} exit {key[2]}: {counts[key]}")
    print(f"{a.runs} mutated files, {sum(counts.values())} runs, {failures} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
