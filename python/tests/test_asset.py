"""sinew.load and Asset.sample / Asset.skin: the same bits as `sinew inspect --pose` and `sinew bake`,
documented shapes and dtypes, read-only arrays, errors, and the GIL released while the runtime works."""

import json
import os
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import sinew
from conftest import ROOT

BIPED = ROOT / "fixtures" / "biped.sinew"


def cli(sinew_bin, *args):
    r = subprocess.run([str(sinew_bin), "--json", *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


def cli_pose(sinew_bin, path, clip, duration, fps=None):
    """`inspect --pose CLIP@0..DURATION`: (times, matrices (T, J, 4, 4) as numpy m[row, col], TRS)."""
    args = ["inspect", path, "--pose", f"{clip}@0..{duration!r}"] + (["--fps", fps] if fps else [])
    r = cli(sinew_bin, *args)
    times = np.array([f["time"] for f in r["frames"]], dtype=np.float32)
    m = np.array([[j["matrix"] for j in f["joints"]] for f in r["frames"]], dtype=np.float32)
    m = m.reshape(len(times), -1, 4, 4).transpose(0, 1, 3, 2)  # column-major -> m[row, col]
    trs = [np.array([[j[k] for j in f["joints"]] for f in r["frames"]], dtype=np.float32)
           for k in ("translation", "rotation", "scale")]
    return times, m, trs, r


# (file, clip, fps for a range or None for the clip's rate)
POSE_CASES = [
    ("bvh/cmu_walk_crlf.bvh", 0, None),
    ("mdl/man.mdl", "walk", None),
    ("gltf/CesiumMan.glb", 0, 24),
    ("gltf/Fox.glb", "Run", None),
    ("ms3d/zombie.ms3d", 0, 15),
]


@pytest.mark.parametrize("rel,clip,fps", POSE_CASES)
def test_sample_gives_the_bits_of_inspect_pose(corpus_dir, sinew_bin, rel, clip, fps):
    path = corpus_dir / rel
    asset = sinew.load(path)
    c = asset.clip(clip)
    times = asset.frame_times(clip, fps)
    cli_times, cli_m, cli_trs, report = cli_pose(sinew_bin, path, c.name, c.duration, fps)
    assert [j["name"] for j in report["joints"]] == list(asset.skeleton.names)
    assert np.array_equal(bits(times), bits(cli_times))
    m = asset.sample(clip, times)
    assert m.shape == (len(times), len(asset.skeleton), 4, 4) and m.dtype == np.float32
    assert np.array_equal(bits(m), bits(cli_m)), rel
    t, r, s = asset.sample_trs(clip, times, local=False)
    for ours, theirs in zip((t, r, s), cli_trs):
        assert np.array_equal(bits(ours), bits(theirs)), rel
    # Times given as float64 seconds are the same float32 times.
    assert np.array_equal(bits(asset.sample(c.name, times.astype(np.float64))), bits(m))


def test_sample_of_a_compressed_sinew_file(corpus_dir, sinew_bin, tmp_path):
    out = tmp_path / "fox.sinew"
    sinew.convert(corpus_dir / "gltf/Fox.glb", out)
    asset = sinew.load(out)
    assert all(c.compressed for c in asset.clips)
    for c in asset.clips:
        times = asset.frame_times(c.name, 20)
        _, cli_m, _, _ = cli_pose(sinew_bin, out, c.name, c.duration, 20)
        assert np.array_equal(bits(asset.sample(c.name, times)), bits(cli_m)), c.name


def read_pc2(path):
    data = path.read_bytes()
    vertices, frames = int.from_bytes(data[16:20], "little"), int.from_bytes(data[28:32], "little")
    return np.frombuffer(data[32:], dtype="<f4").reshape(frames, vertices, 3)


@pytest.mark.parametrize("rel,clip,options", [
    ("mdl/man.mdl", "walk", {}),
    ("gltf/CesiumMan.glb", None, {"fps": 24}),
    ("ms3d/zombie.ms3d", None, {"lod": 1}),
])
def test_skin_gives_the_bits_of_bake(corpus_dir, sinew_bin, tmp_path, rel, clip, options):
    path = corpus_dir / rel
    lod = options.get("lod", 0)
    asset = sinew.load(path, lods=lod > 0)
    clip = clip if clip is not None else asset.clips[0].name
    # asset.skin skins one mesh (mesh 0 by default); bake's default is the model's default body.
    args = ["bake", path, "--clip", clip, "--mesh", "0", "--format", "pc2", "-o", tmp_path / "c.pc2"]
    for k, v in options.items():
        args += [f"--{k}", v]
    cli(sinew_bin, *args)
    baked = read_pc2(tmp_path / "c.pc2")
    times = asset.frame_times(clip, options.get("fps"))
    positions = asset.skin(clip, times, lod=lod)
    v = len(asset.meshes[0].lods[lod].positions)
    assert positions.shape == (len(times), v, 3) == baked.shape and positions.dtype == np.float32
    assert np.array_equal(bits(positions), bits(baked)), rel


def test_parts_are_documented_shapes_dtypes_and_read_only(corpus_dir, sinew_bin):
    path = corpus_dir / "mdl/man.mdl"
    asset = sinew.load(path)
    report = cli(sinew_bin, "inspect", path)
    sk = asset.skeleton
    j = report["summary"]["joints"]
    assert len(sk) == j == 8 and sk.names[0] == "Root" and sk.index("Pelvis") == 1
    expected = {"parents": ((j,), np.int32), "bind_translations": ((j, 3), np.float32),
                "bind_rotations": ((j, 4), np.float32), "bind_scales": ((j, 3), np.float32),
                "bind_local": ((j, 4, 4), np.float32), "bind_model": ((j, 4, 4), np.float32),
                "inverse_bind": ((j, 4, 4), np.float32)}
    for name, (shape, dtype) in expected.items():
        a = getattr(sk, name)
        assert a.shape == shape and a.dtype == dtype, name
        assert not a.flags.writeable, name
        with pytest.raises(ValueError):
            a[0] = 0
    assert list(sk.parents) == [-1 if x["parent"] is None else x["parent"] for x in report["skeleton"]["joints"]]
    for x in report["skeleton"]["joints"]:
        assert np.array_equal(bits(sk.bind_rotations[x["index"]]), bits(x["bind"]["rotation"]))
    # The bind pose in model space inverts the inverse bind matrices (MDL: no matrices of its own).
    assert np.allclose(sk.bind_model @ sk.inverse_bind, np.eye(4), atol=1e-5)
    # Clips.
    assert [c.name for c in asset.clips] == [c["name"] for c in report["clips"]]
    for c, r in zip(asset.clips, report["clips"]):
        assert (np.float32(c.duration), c.sample_rate, c.looping) == (np.float32(r["duration"]), r["sample_rate"], r["looping"])
        assert c.times.dtype == np.float32 and not c.times.flags.writeable
        # The runtime keeps key times for animated channels: a clip whose every channel is
        # constant (a still pose) has the one time 0.
        if len(c.times) == 1:
            assert c.times[0] == 0
            assert np.array_equal(bits(asset.sample(c.name, [0.0])), bits(asset.sample(c.name, [c.duration])))
        else:
            assert len(c.times) == r["key_times"]
        assert [sk.names[i] for i in c.driven] == r["driven_joints"] and c.driven.dtype == np.int32
        assert list(c.unbound) == r["unmatched_joints"]
    # Meshes: counts and submesh ranges as inspect reports them.
    # man.mdl: a headless body and three heads, each submodel a mesh of its own.
    assert len(asset.meshes) == len(report["meshes"]) == 4
    for m, r in zip(asset.meshes, report["meshes"]):
        lod = m.lods[0]
        v, f = r["vertices"], r["triangles"]
        assert m.name == r["name"]
        for name, shape, dtype in [("positions", (v, 3), np.float32), ("normals", (v, 3), np.float32),
                                   ("uvs", (v, 2), np.float32), ("indices", (f, 3), np.uint32),
                                   ("joint_indices", (v, 4), np.uint16), ("joint_weights", (v, 4), np.float32),
                                   ("submeshes", (len(r["submeshes"]), 2), np.uint32)]:
            a = getattr(lod, name)
            assert a.shape == shape and a.dtype == dtype and not a.flags.writeable, (m.name, name)
        assert lod.submeshes.tolist() == [[s["first_index"], s["index_count"]] for s in r["submeshes"]]
        assert list(lod.materials) == [s["material"] for s in r["submeshes"]]
        assert np.allclose(lod.joint_weights.sum(axis=1), 1, atol=1e-5)
        assert lod.indices.max() < v and lod.joint_indices.max() < j
        assert lod.source_vertex is not None and len(lod.source_vertex) == v
        assert lod.source_vertex_count == r["source_vertices"]
    assert [m.name for m in asset.materials] == [m["name"] for m in report["materials"]]
    assert asset.materials[0].base_color.shape == (4,)
    # Half-Life game data: the schema and values of inspect's `game`.
    assert asset.game == report["game"]
    assert asset.game["clips"][1]["activity_name"] == "ACT_WALK"


def test_masks_and_a_static_mesh(corpus_dir, sinew_bin):
    asset = sinew.load(BIPED)
    report = cli(sinew_bin, "inspect", BIPED)
    assert [m.name for m in asset.masks] == ["upper", "lower"]
    for m, r in zip(asset.masks, report["masks"]):
        assert list(m.joints) == [w["joint"] for w in r["weights"]]
        assert m.weights.tolist() == [w["weight"] for w in r["weights"]]
        assert m.per_joint.shape == (len(asset.skeleton),) and not m.per_joint.flags.writeable
        assert sorted(asset.skeleton.names[i] for i in np.flatnonzero(m.per_joint)) == sorted(m.joints)
    prop = sinew.load(ROOT / "fixtures" / "prop.obj")
    assert prop.skeleton is None and prop.clips == () and prop.game is None
    lod = prop.meshes[0].lods[0]
    assert not lod.skinned and lod.joint_indices.shape == (0, 4) and lod.positions.shape[0] > 0
    with pytest.raises(sinew.UsageError, match="no skeleton"):
        prop.sample(0, [0.0])


def test_local_transforms(corpus_dir):
    asset = sinew.load(corpus_dir / "gltf/CesiumMan.glb")
    sk = asset.skeleton
    times = np.linspace(0, asset.clips[0].duration, 7)
    model = asset.sample(0, times)
    local = asset.sample(0, times, local=True)
    roots = np.flatnonzero(sk.parents < 0)
    children = np.flatnonzero(sk.parents >= 0)
    # A root's local matrix is its model matrix (the runtime's formulas for both).
    assert np.array_equal(local[:, roots], model[:, roots])
    # model[j] = model[parent] @ local[j], up to rounding.
    composed = model[:, sk.parents[children]] @ local[:, children]
    assert np.allclose(composed, model[:, children], atol=1e-5)
    t, r, s = asset.sample_trs(0, times)
    assert t.shape == (7, len(sk), 3) and r.shape == (7, len(sk), 4) and s.shape == (7, len(sk), 3)
    assert np.array_equal(bits(t), bits(local[..., :3, 3]))
    assert np.allclose(np.linalg.norm(r, axis=-1), 1, atol=1e-5)
    # m[row, col]: the bottom row of every matrix is 0 0 0 1.
    assert np.array_equal(local[:, :, 3], np.broadcast_to([0, 0, 0, 1], local[:, :, 3].shape))
    assert np.array_equal(model[:, :, 3], np.broadcast_to([0, 0, 0, 1], model[:, :, 3].shape))


def test_out_buffers(corpus_dir):
    asset = sinew.load(corpus_dir / "mdl/man.mdl")
    times = asset.frame_times("walk")
    out = np.full((len(times), 8, 4, 4), np.nan, np.float32)
    got = asset.sample("walk", times, out=out)
    assert got is out and not np.isnan(out).any()
    assert np.array_equal(bits(out), bits(asset.sample("walk", times)))
    v = len(asset.meshes[0].lods[0].positions)
    pos = np.zeros((len(times), v, 3), np.float32)
    assert asset.skin("walk", times, out=pos) is pos
    assert np.array_equal(bits(pos), bits(asset.skin("walk", times, mesh="studio/reference_headless")))
    for bad in [np.zeros((len(times), 8, 4, 4), np.float64), np.zeros((len(times) + 1, 8, 4, 4), np.float32),
                np.zeros((len(times), 8, 4, 8), np.float32)[..., :4], [[0.0]]]:
        with pytest.raises(sinew.UsageError, match="out"):
            asset.sample("walk", times, out=bad)
    frozen = np.zeros((len(times), 8, 4, 4), np.float32)
    frozen.flags.writeable = False
    with pytest.raises(sinew.UsageError, match="writeable"):
        asset.sample("walk", times, out=frozen)


def test_errors(corpus_dir, tmp_path):
    with pytest.raises(sinew.InputError, match="no such file"):
        sinew.load(tmp_path / "missing.bvh")
    truncated = tmp_path / "cut.mdl"
    truncated.write_bytes((corpus_dir / "mdl/man.mdl").read_bytes()[:5000])
    with pytest.raises(sinew.InputError, match="cut.mdl.*truncated"):
        sinew.load(truncated)
    with pytest.raises(sinew.InputError, match="at byte 300624"):
        sinew.load(corpus_dir / "ms3d/malformed/Wuson_crlf_damaged.ms3d")
    asset = sinew.load(corpus_dir / "mdl/man.mdl")
    with pytest.raises(sinew.UsageError, match='no clip "run"; the file has: reference, walk'):
        asset.sample("run", [0.0])
    with pytest.raises(sinew.UsageError, match="clip 9 does not exist"):
        asset.skin(9, [0.0])
    d = asset.clip("walk").duration
    with pytest.raises(sinew.UsageError, match=r"time 2 \(0.9 s\) is outside clip \"walk\""):
        asset.sample("walk", [0.0, 0.5, 0.9])
    with pytest.raises(sinew.UsageError, match="time 0"):
        asset.skin("walk", [-0.01])
    with pytest.raises(sinew.UsageError, match="not a finite"):
        asset.sample("walk", [np.nan], wrap=True)
    with pytest.raises(sinew.UsageError, match="1-D"):
        asset.sample("walk", [[0.0]])
    with pytest.raises(sinew.UsageError, match="LOD 1 does not exist"):
        asset.skin("walk", [0.0], lod=1)
    with pytest.raises(sinew.UsageError, match="LOD -1 does not exist"):
        asset.skin("walk", [0.0], lod=-1)
    with pytest.raises(sinew.UsageError, match="clip -1 does not exist"):
        asset.sample(-1, [0.0])
    with pytest.raises(sinew.UsageError, match="mesh 5 does not exist"):
        asset.skin("walk", [0.0], mesh=5)
    with pytest.raises(sinew.UsageError, match='no mesh "x"'):
        asset.skin("walk", [0.0], mesh="x")
    with pytest.raises(sinew.UsageError, match="ms3d_position_keys"):
        sinew.load(corpus_dir / "mdl/man.mdl", ms3d_position_keys="sideways")
    # wrap=True applies the runtime's rule: a looping clip wraps, a non-looping one clamps.
    assert asset.clip("walk").looping
    quarter = asset.sample("walk", [d / 4])
    assert np.allclose(asset.sample("walk", [d + d / 4], wrap=True), quarter, atol=1e-4)
    cesium = sinew.load(corpus_dir / "gltf/CesiumMan.glb")
    assert not cesium.clips[0].looping
    end = cesium.clips[0].duration
    assert np.array_equal(bits(cesium.sample(0, [-1.0], wrap=True)), bits(cesium.sample(0, [0.0])))
    assert np.array_equal(bits(cesium.skin(0, [end + 5], wrap=True)), bits(cesium.skin(0, [end])))


def test_the_gil_is_released_while_sampling_and_skinning(corpus_dir):
    asset = sinew.load(corpus_dir / "gltf/Fox.glb")
    clip = asset.clip("Run")
    for call in [lambda t: asset.skin("Run", t), lambda t: asset.sample("Run", t)]:
        n = 256
        while True:
            times = np.linspace(0, clip.duration, n, dtype=np.float32)
            span = {}

            def work():
                span["start"] = time.perf_counter()
                call(times)
                span["end"] = time.perf_counter()

            ticks = []
            t = threading.Thread(target=work)
            t.start()
            while t.is_alive():
                ticks.append(time.perf_counter())
                time.sleep(0.0005)
            t.join()
            if span["end"] - span["start"] >= 0.03 or n >= 1 << 20:
                break
            n *= 4
        inside = [x for x in ticks if span["start"] < x < span["end"]]
        # This thread kept running Python while the other was inside sinew (30 ms or more).
        assert span["end"] - span["start"] >= 0.03
        assert len(inside) >= 5, (len(inside), span["end"] - span["start"])


def test_every_public_name_is_documented_and_the_stubs_match_the_extension(tmp_path):
    for name in sinew.__all__:
        obj = getattr(sinew, name)
        if callable(obj):
            assert obj.__doc__ and obj.__doc__.strip(), name
    for cls in [sinew.Asset, sinew.Skeleton, sinew.Clip, sinew.Lod]:
        for name, member in vars(cls).items():
            if callable(member) and not name.startswith("_"):
                assert member.__doc__, f"{cls.__name__}.{name}"
    mypy = pytest.importorskip("mypy")
    assert mypy
    # In a scratch directory: stubtest writes its cache to the working directory.
    env = {**os.environ, "MYPY_CACHE_DIR": str(tmp_path / "mypy")}
    r = subprocess.run([sys.executable, "-m", "mypy.stubtest", "sinew._sinew"], capture_output=True, text=True,
                       env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run([sys.executable, "-m", "mypy", "--follow-imports=silent", "--strict",
                        str(ROOT / "python" / "sinew" / "asset.py")], capture_output=True, text=True, env=env,
                       cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr


def test_a_missing_half_life_companion_is_an_error_unless_allowed(corpus_dir, tmp_path):
    # man.mdl keeps its textures in manT.mdl: without it loading fails, naming the missing file, as
    # `sinew convert` does; allow_missing=True loads the model without its textures.
    alone = tmp_path / "man.mdl"
    alone.write_bytes((corpus_dir / "mdl/man.mdl").read_bytes())
    (tmp_path / "man01.mdl").write_bytes((corpus_dir / "mdl/man01.mdl").read_bytes())
    with pytest.raises(sinew.InputError, match="manT.mdl"):
        sinew.load(alone)
    asset = sinew.load(alone, allow_missing=True)
    whole = sinew.load(corpus_dir / "mdl/man.mdl")
    assert [c.name for c in asset.clips] == [c.name for c in whole.clips]
    assert asset.skeleton.names == whole.skeleton.names
