#!/usr/bin/env python3
"""Foot sliding over a folder of motion files: how fast each foot moves along the ground while it
is planted. A clean capture or a good retarget keeps planted feet still; sliding shows up as speed
during contact. (docs/python.md walks through it.)

python foot_sliding.py FOLDER [--up y] [--fps 60] [--contact 0.04] [--json]

For every file sinew reads in FOLDER, every clip, every joint whose name contains "foot" or "toe"
(any case; not BVH end sites): the joint's model-space position at every frame (sinew's runtime,
`Asset.sample`), its height along the up axis, its contact frames (height within `--contact` times
the skeleton's bind-pose height of the lowest point any foot reaches in the clip), and its speed
across the ground between consecutive contact frames. Prints one line per foot: contact frames, the median and the largest sliding speed
(model units per second). Files that fail to load are reported and skipped; the exit code is 1 when
any did.
"""

import argparse
import json
import pathlib
import sys

import numpy as np

import sinew

EXTENSIONS = {".bvh", ".glb", ".gltf", ".ms3d", ".mdl", ".smd", ".sinew"}


def feet(skeleton):
    """Joints named like feet or toes (not the end points BVH files add after them)."""
    return [i for i, n in enumerate(skeleton.names)
            if ("foot" in n.lower() or "toe" in n.lower()) and not n.endswith("_end")]


def sliding(asset, clip, up, fps, contact):
    """Per foot joint: (name, contact frames, median speed, largest speed) for one clip."""
    times = asset.frame_times(clip, fps)
    model = asset.sample(clip, times)                  # (T, J, 4, 4), m[row, col]
    positions = model[:, :, :3, 3]                     # (T, J, 3) joint positions
    bind = asset.skeleton.bind_model[:, :3, 3]         # (J, 3) bind-pose joint positions
    band = contact * (np.ptp(bind[:, up]) or 1.0)
    ground = [a for a in range(3) if a != up]
    dt = np.diff(times)
    joints = feet(asset.skeleton)
    if not joints:
        return []
    floor = positions[:, joints, up].min()             # the lowest any foot gets in the clip
    rows = []
    for j in joints:
        planted = positions[:, j, up] <= floor + band
        both = planted[1:] & planted[:-1]              # consecutive frames both in contact
        step = np.linalg.norm(np.diff(positions[:, j][:, ground], axis=0), axis=1)
        speed = step[both] / dt[both]
        rows.append((asset.skeleton.names[j], int(planted.sum()),
                     float(np.median(speed)) if speed.size else 0.0,
                     float(speed.max()) if speed.size else 0.0))
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folder", type=pathlib.Path)
    p.add_argument("--up", choices="xyz", default="y", help="the up axis of the files (default y)")
    p.add_argument("--fps", type=float, default=None, help="frames per second (default: each clip's rate)")
    p.add_argument("--contact", type=float, default=0.04,
                   help="contact band above a foot's lowest point, as a fraction of the skeleton's height")
    p.add_argument("--json", action="store_true", help="print JSON instead of text")
    args = p.parse_args()
    up = "xyz".index(args.up)
    report, failed = [], 0
    for path in sorted(f for f in args.folder.iterdir() if f.suffix.lower() in EXTENSIONS):
        try:
            asset = sinew.load(path)
        except sinew.SinewError as e:
            failed += 1
            report.append({"file": path.name, "error": str(e)})
            continue
        if asset.skeleton is None:
            continue
        for clip in asset.clips:
            for name, frames, median, largest in sliding(asset, clip.name, up, args.fps, args.contact):
                report.append({"file": path.name, "clip": clip.name, "joint": name, "contact_frames": frames,
                               "median_speed": median, "max_speed": largest})
    if args.json:
        print(json.dumps(report, indent=1))
    else:
        for r in report:
            if "error" in r:
                print(f"{r['file']}: {r['error']}")
            else:
                print(f"{r['file']:24} {r['clip'][:16]:16} {r['joint'][:16]:16} {r['contact_frames']:5d} contact "
                      f"frames, sliding median {r['median_speed']:8.3f}, max {r['max_speed']:8.3f} units/s")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
