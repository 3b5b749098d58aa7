#!/usr/bin/env python3
"""Alternating whole-process timings of any commands (sinew binaries, peers such as gltf2ozz).

tools/alternate.py ROUNDS NAME 'COMMAND ARGS' [NAME 'COMMAND ARGS' ...]

Runs every command once to warm up, then ROUNDS rounds of each command in turn (no shell: the
command line is split with shlex), each in one scratch directory (gltf2ozz writes its outputs to
the working directory; arguments naming an existing file or directory relative to the caller's
directory are made absolute first, so relative inputs work), and prints the median, 25th and 75th percentile wall time of each in ms.
Alternating puts every command under the same load of a shared machine. Used for the "Convert
time, session 9" tables of docs/performance.md."""
import os, shlex, statistics, subprocess, sys, tempfile, time

rounds = int(sys.argv[1])
cmds = [
    (sys.argv[i], [os.path.abspath(a) if os.path.exists(a) else a for a in shlex.split(sys.argv[i + 1])])
    for i in range(2, len(sys.argv) - 1, 2)
]
scratch = tempfile.mkdtemp()


def run(cmd):
    start = time.perf_counter()
    subprocess.run(cmd, check=True, cwd=scratch, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return (time.perf_counter() - start) * 1000


for _, cmd in cmds:
    run(cmd)
times = {name: [] for name, _ in cmds}
for _ in range(rounds):
    for name, cmd in cmds:
        times[name].append(run(cmd))
for name, _ in cmds:
    v = sorted(times[name])
    print(f"{name:16} median {statistics.median(v):9.1f} ms  p25 {v[len(v) // 4]:9.1f}  p75 {v[3 * len(v) // 4]:9.1f}")
