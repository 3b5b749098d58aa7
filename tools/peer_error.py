#!/usr/bin/env python3
"""Error of a peer's compressed clip (gltf2ozz's .ozz) and of sinew's output against the source,
measured with sinew's metric (docs/performance.md, session 28): for every joint, three points
`--distance` model units along its model-space axes (a joint of bind scale 1), the largest distance
between the source's points and the other's, worst over joints and times. Times: the clip's frames
at FPS from 0 to its duration, so choose FPS so that they are the source's key times (a 30 Hz
capture: 30; Fox: 24); between key times neither tool promises anything.

    tools/peer_error.py SOURCE.glb CLIP --ozz-dir DIR [--sinew OUT.sinew ...] [--fps 30] [--distance 0.1]

The source and sinew outputs are evaluated by `sinew inspect --pose CLIP@0..D --fps F --json` (the
runtime's model matrices); gltf2ozz's by tools/ozz_sample.cc (ozz's SamplingJob and
LocalToModelJob), built against the peers' ozz (`../shared/peers/install.sh`):

    g++ -O2 -std=c++17 -I$PEERS/ozz-src/include tools/ozz_sample.cc \\
        $PEERS/ozz-build/src/animation/runtime/libozz_animation.a \\
        $PEERS/ozz-build/src/base/libozz_base.a -o target/ozz_sample

DIR is where gltf2ozz wrote skeleton.ozz and CLIP.ozz. Joints are matched by name (ozz's
`node_2` also matches sinew's `node2`, which is not always the same joint: check the names).
Needs numpy (PEERS/venv)."""
import argparse, json, os, subprocess, sys
import numpy as np

MAIN = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ap = argparse.ArgumentParser()
ap.add_argument("source"); ap.add_argument("clip")
ap.add_argument("--ozz-dir"); ap.add_argument("--sinew", action="append", default=[])
ap.add_argument("--fps", type=float, default=30.0); ap.add_argument("--distance", type=float, default=0.1)
ap.add_argument("--sinew-bin", default=f"{MAIN}/target/release/sinew")
ap.add_argument("--ozz-sample", default=f"{MAIN}/target/ozz_sample")
a = ap.parse_args()


def pose(path):
    """Times and, per joint name, the model matrices (T, 4, 4) as columns (m[t, c] is column c)."""
    info = json.loads(subprocess.run([a.sinew_bin, "inspect", path, "--json"], capture_output=True, text=True, check=True).stdout)
    duration = next(c["duration"] for c in info["clips"] if c["name"] == a.clip)
    out = subprocess.run([a.sinew_bin, "inspect", path, "--pose", f"{a.clip}@0..{duration}", "--fps", str(a.fps), "--json"],
                         capture_output=True, text=True, check=True).stdout
    frames = json.loads(out)["frames"]
    mats = {}
    for f in frames:
        for j in f["joints"]:
            mats.setdefault(j["name"], []).append(np.array(j["matrix"], dtype=np.float64).reshape(4, 4))
    return [f["time"] for f in frames], {k: np.array(v) for k, v in mats.items()}


def ozz(times):
    out = subprocess.run([a.ozz_sample, f"{a.ozz_dir}/skeleton.ozz", f"{a.ozz_dir}/{a.clip}.ozz"] + [repr(t) for t in times],
                         capture_output=True, text=True, check=True).stdout
    mats = {}
    for line in out.splitlines():
        p = line.split()
        if len(p) == 17:
            mats.setdefault(p[0], []).append(np.array([float(x) for x in p[1:]]).reshape(4, 4))
    return {k: np.array(v) for k, v in mats.items()}


def points(m):
    return np.stack([m[:, 3, :3] + a.distance * m[:, c, :3] for c in range(3)], axis=1)


def error(src, times, other):
    if not set(other) & set(src):
        other = {k.replace("_", ""): v for k, v in other.items()}
    worst, where, matched = 0.0, None, 0
    for name, m in src.items():
        if name not in other:
            continue
        matched += 1
        e = np.linalg.norm(points(m) - points(other[name][: len(m)]), axis=2).max(axis=1)
        if e.max() > worst:
            worst, where = float(e.max()), (name, times[int(e.argmax())])
    return {"max_error": worst, "at": where, "joints_matched": matched}


times, src = pose(a.source)
report = {"clip": a.clip, "times": len(times),
          "largest_coordinate": float(max(np.abs(points(m)).max() for m in src.values()))}
if a.ozz_dir:
    report["gltf2ozz"] = error(src, times, ozz(times))
for s in a.sinew:
    report[s] = error(src, times, pose(s)[1])
json.dump(report, sys.stdout)
print()
