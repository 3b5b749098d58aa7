"""The examples in python/examples run on the corpus and find what they should."""

import json
import subprocess
import sys

from conftest import ROOT

EXAMPLES = ROOT / "python" / "examples"


def run(*args):
    return subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True)


def test_foot_sliding_over_folders(corpus_dir):
    r = run(EXAMPLES / "foot_sliding.py", corpus_dir / "bvh", "--json")
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout)
    by = {(x["file"], x["joint"]): x for x in rows}
    # Every BVH with feet is there, with its four foot and toe joints (end sites left out).
    assert {f for f, _ in by} == {"Boxing_Toes.bvh", "cmu_01_01.bvh", "cmu_walk_crlf.bvh", "pfnn_hierarchy_crlf.bvh"}
    assert {j for f, j in by if f == "cmu_walk_crlf.bvh"} == {"LeftFoot", "RightFoot", "LeftToeBase", "RightToeBase"}
    # The PFNN hierarchy file holds one still pose: every foot planted, nothing slides.
    still = [x for x in rows if x["file"] == "pfnn_hierarchy_crlf.bvh"]
    assert all(x["contact_frames"] == 60 and x["max_speed"] == 0 for x in still)
    # A captured walk plants its toes and barely slides them (median under 3 units/s, the walk
    # moves at about 20 units/s).
    toe = by[("cmu_walk_crlf.bvh", "LeftToeBase")]
    assert toe["contact_frames"] > 20 and toe["median_speed"] < 3
    # The Fox walks and runs in place: a planted foot moves back at walking speed; standing still
    # (Survey) it does not.
    r = run(EXAMPLES / "foot_sliding.py", corpus_dir / "gltf", "--json")
    assert r.returncode == 0, r.stderr
    fox = {(x["clip"], x["joint"]): x for x in json.loads(r.stdout) if x["file"] == "Fox.glb"}
    assert fox[("Walk", "b_RightFoot02_022")]["median_speed"] > 50
    assert fox[("Survey", "b_RightFoot02_022")]["max_speed"] < 0.1
    # A file sinew cannot read is reported with its message, and the exit code says so.
    r = run(EXAMPLES / "foot_sliding.py", corpus_dir / "mdl", "--up", "z", "--json")
    assert r.returncode == 1
    errors = [x for x in json.loads(r.stdout) if "error" in x]
    assert [x["file"] for x in errors] == ["man01.mdl"] and "sequence-group" in errors[0]["error"]
