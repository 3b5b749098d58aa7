#!/usr/bin/env python3
"""sinew.load + Asset.sample against fairmotion's bvh.load + Pose.get_transform, alternating, in one
process (issue 33, goal 3; docs/scale.md).

python tools/python_speed.py FILE.bvh [ROUNDS]

Needs a Python with both packages: sinew (the wheel `maturin build --release` writes into
target/wheels) and fairmotion 0.0.4 (`pip install numpy scipy` and `pip install --no-deps
fairmotion==0.0.4`: its bvh module needs only numpy and scipy; its declared torch==1.4.0 does not
install on current Pythons). Keep that venv outside the repository.

Each round times, in turn, the two ways of getting every joint's model-space 4x4 transform at every
frame of the file (the 120 Hz of cmu_01_01.bvh):
- fairmotion: `bvh.load(path)`, then `pose.get_transform(joint, local=False)` for every pose and
  joint, stacked into one (frames, joints, 4, 4) array;
- sinew: `sinew.load(path)`, then `asset.sample(0, asset.clips[0].times)` (the clip's key times,
  one per frame of the file).
It prints the median, 25th and 75th percentile wall time of each (and of sinew's two calls) and the
ratio of the medians, then
checks that both computed the same motion: the largest distance between the joint positions of
joints present in both (by name), in the file's units.
"""
import statistics
import sys
import time

import numpy as np
import sinew
from fairmotion.data import bvh

path = sys.argv[1]
rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 5


def with_fairmotion():
    motion = bvh.load(path)
    joints = motion.skel.joints
    out = np.empty((len(motion.poses), len(joints), 4, 4))
    for i, pose in enumerate(motion.poses):
        for j, joint in enumerate(joints):
            out[i, j] = pose.get_transform(joint, local=False)
    return [j.name for j in joints], out


parts = {"sinew.load": [], "asset.sample": []}


def with_sinew():
    start = time.perf_counter()
    asset = sinew.load(path)
    loaded = time.perf_counter()
    out = asset.sample(0, asset.clips[0].times)
    parts["sinew.load"].append((loaded - start) * 1000)
    parts["asset.sample"].append((time.perf_counter() - loaded) * 1000)
    return list(asset.skeleton.names), out


def timed(f):
    start = time.perf_counter()
    result = f()
    return (time.perf_counter() - start) * 1000, result


timed(with_fairmotion)
timed(with_sinew)
for v in parts.values():
    v.clear()
times = {"fairmotion": [], "sinew": []}
for _ in range(rounds):
    ms, fm = timed(with_fairmotion)
    times["fairmotion"].append(ms)
    ms, sn = timed(with_sinew)
    times["sinew"].append(ms)
for name, v in times.items():
    v = sorted(v)
    print(f"{name:10} median {statistics.median(v):9.1f} ms  p25 {v[len(v) // 4]:9.1f}  p75 {v[3 * len(v) // 4]:9.1f}")
for name, v in parts.items():
    print(f"  {name:12} median {statistics.median(v):7.1f} ms")
ratio = statistics.median(times["fairmotion"]) / statistics.median(times["sinew"])
print(f"ratio of medians: {ratio:.0f}x")

(fm_names, fm_out), (sn_names, sn_out) = fm, sn
common = [n for n in fm_names if n in sn_names]
a = fm_out[:, [fm_names.index(n) for n in common], :3, 3]
b = sn_out[:, [sn_names.index(n) for n in common], :3, 3]
print(f"frames: fairmotion {fm_out.shape[0]}, sinew {sn_out.shape[0]}; joints in both: {len(common)}")
n = min(len(a), len(b))
print(f"largest joint position difference: {np.abs(a[:n] - b[:n]).max():.2e} units")
