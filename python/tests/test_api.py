"""The Python functions give what the command line gives: same reports, same bytes, same errors."""

import json
import pathlib
import subprocess
import threading
import time

import numpy as np
import pytest

import sinew


def cli(sinew_bin, *args):
    r = subprocess.run([str(sinew_bin), "--json", *map(str, args)], capture_output=True, text=True)
    return r.returncode, (json.loads(r.stdout) if r.stdout.strip() else None), r.stderr


def test_inspect_matches_the_command_line(corpus_dir, sinew_bin):
    for rel in ["mdl/man.mdl", "gltf/CesiumMan.glb", "bvh/cmu_walk_crlf.bvh"]:
        path = corpus_dir / rel
        code, report, _ = cli(sinew_bin, "inspect", path)
        assert code == 0
        assert sinew.inspect(path) == report
    r = sinew.inspect(corpus_dir / "mdl/man.mdl")
    assert r["summary"]["joints"] == 8
    assert [c["name"] for c in r["clips"]][:2] == ["reference", "walk"]
    assert r["game"]["clips"][1]["activity_name"] == "ACT_WALK"


def test_convert_writes_the_same_bytes_as_the_command_line(corpus_dir, sinew_bin, tmp_path):
    for rel, options, args in [
        ("gltf/CesiumMan.glb", {}, []),
        ("ms3d/zombie.ms3d", {"lod": "0.6,0.3", "tolerance": 0.01}, ["--lod", "0.6,0.3", "--tolerance", "0.01"]),
        ("mdl/man.mdl", {"no_textures": True}, ["--no-textures"]),
    ]:
        src = corpus_dir / rel
        a, b = tmp_path / "py" / (src.stem + ".sinew"), tmp_path / "cli" / (src.stem + ".sinew")
        a.parent.mkdir(exist_ok=True)
        b.parent.mkdir(exist_ok=True)
        report = sinew.convert(src, a, **options)
        code, cli_report, _ = cli(sinew_bin, "convert", src, "-o", b, *args)
        assert code == 0
        assert a.read_bytes() == b.read_bytes(), rel
        assert report["files"][0]["bytes"] == a.stat().st_size
        for key in ["format", "joints", "meshes", "clips", "diagnostics"]:
            assert report["files"][0][key] == cli_report["files"][0][key], (rel, key)


def test_a_batch_reports_failures_without_raising(corpus_dir, tmp_path):
    report = sinew.convert([corpus_dir / "ms3d/cross.ms3d", corpus_dir / "ms3d/malformed/Wuson_crlf_damaged.ms3d"],
                           out_dir=tmp_path / "new" / "dir")
    assert (report["converted"], report["failed"]) == (1, 1)
    bad = report["files"][1]
    assert bad["status"] == "failed"
    assert "joints at byte 300624" in bad["error"]
    assert (tmp_path / "new" / "dir" / "cross.sinew").is_file()


def test_errors_carry_the_command_lines_message(corpus_dir, tmp_path):
    with pytest.raises(sinew.InputError) as e:
        sinew.convert(corpus_dir / "ms3d/malformed/Wuson_crlf_damaged.ms3d", tmp_path / "w.sinew")
    assert "Wuson_crlf_damaged.ms3d" in str(e.value) and "at byte 300624" in str(e.value)
    assert isinstance(e.value, sinew.SinewError)
    assert not (tmp_path / "w.sinew").exists()
    with pytest.raises(sinew.UsageError):
        sinew.convert(corpus_dir / "ms3d/cross.ms3d", tmp_path / "c.sinew", lod_influences="many")
    truncated = tmp_path / "cut.mdl"
    truncated.write_bytes((corpus_dir / "mdl/man.mdl").read_bytes()[:5000])
    with pytest.raises(sinew.InputError) as e:
        sinew.inspect(truncated)
    assert "truncated" in str(e.value) and "cut.mdl" in str(e.value)


def test_bake_writers_and_verify(corpus_dir, sinew_bin, tmp_path):
    src = corpus_dir / "mdl/man.mdl"
    positions = sinew.bake(src, clip="walk")
    assert positions.shape == (26, 144, 3) and positions.dtype == np.float32
    code, report, _ = cli(sinew_bin, "bake", src, "--clip", "walk", "--format", "pc2", "-o", tmp_path / "cli.pc2")
    assert code == 0
    cli_pc2 = (tmp_path / "cli.pc2").read_bytes()
    # PC2: a 32-byte header, then frames x vertices x 3 little-endian floats: the same numbers.
    assert np.array_equal(np.frombuffer(cli_pc2[32:], dtype="<f4").reshape(26, 144, 3), positions)
    sinew.write_pc2(tmp_path / "py.pc2", positions, fps=30)
    assert (tmp_path / "py.pc2").read_bytes() == cli_pc2
    sinew.write_mdd(tmp_path / "py.mdd", positions, fps=30)
    mdd = (tmp_path / "py.mdd").read_bytes()
    assert int.from_bytes(mdd[:4], "big") == 26 and int.from_bytes(mdd[4:8], "big") == 144
    # A cache baked through Python's wrapper of `sinew bake` verifies; a damaged one does not.
    sinew.bake_to(src, tmp_path / "walk.pc2", format="pc2", clip="walk")
    assert sinew.verify(tmp_path / "walk.pc2", src)["identical"] is True
    data = bytearray((tmp_path / "walk.pc2").read_bytes())
    data[100] ^= 0x10
    (tmp_path / "walk.pc2").write_bytes(bytes(data))
    v = sinew.verify(tmp_path / "walk.pc2", src)
    assert v["identical"] is False and v["mismatches"] >= 1
    with pytest.raises(sinew.UsageError):
        sinew.write_pc2(tmp_path / "bad.pc2", positions[:, :, :2], fps=30)


def test_map_returns_the_mapping(corpus_dir, sinew_bin):
    rig, motion = corpus_dir / "ms3d/zombie.ms3d", corpus_dir / "bvh/cmu_walk_crlf.bvh"
    m = sinew.map(rig, motion)
    code, report, _ = cli(sinew_bin, "map", rig, motion)
    assert m == report
    assert m["bound"] == sum(1 for e in m["entries"] if e["motion"] is not None)


def test_export_and_pictures_write_the_command_lines_bytes(corpus_dir, sinew_bin, tmp_path):
    src = corpus_dir / "gltf/Fox.glb"
    r = sinew.export(src, tmp_path / "fox.glb")
    assert r["animations"] == 3 and r["joints"] == 24
    code, _, _ = cli(sinew_bin, "export", src, "-o", tmp_path / "fox_cli.glb")
    assert code == 0
    assert (tmp_path / "fox.glb").read_bytes() == (tmp_path / "fox_cli.glb").read_bytes()
    p = sinew.preview(src, tmp_path / "fox.png", clip="Walk", frames=4)
    assert (p["width"], p["rows"]) == (4 * 256, 2)
    assert (tmp_path / "fox.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    m = sinew.map(corpus_dir / "ms3d/zombie.ms3d", corpus_dir / "bvh/cmu_walk_crlf.bvh", png=tmp_path / "m.png")
    assert m["picture"]["width"] == 1200 and (tmp_path / "m.png").is_file()


def test_the_gil_is_released_while_sinew_works(corpus_dir, tmp_path):
    ticks = []
    done = threading.Event()

    def work():
        sinew.convert(corpus_dir / "bvh/cmu_walk_crlf.bvh", tmp_path / "walk.sinew")
        done.set()

    t = threading.Thread(target=work)
    t.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    t.join()
    # Python code kept running during the conversion (it takes tens of milliseconds at least).
    assert len(ticks) >= 5


def test_convert_takes_strict_incremental_and_allow_missing(corpus_dir, tmp_path):
    import shutil

    folder = tmp_path / "models"
    folder.mkdir()
    # cube_mtllib_after_g.obj has warnings (its material library is not there), triangle.smd none.
    for rel in ["obj/cube_mtllib_after_g.obj", "smd/triangle.smd", "mdl/manT.mdl"]:
        shutil.copy(corpus_dir / rel, folder / pathlib.Path(rel).name)
    report = sinew.convert(folder, out_dir=tmp_path / "out", strict=True, lod="none")
    statuses = {pathlib.Path(f["input"]).name: f["status"] for f in report["files"]}
    assert statuses == {"cube_mtllib_after_g.obj": "failed", "triangle.smd": "converted"}
    assert report["strict"] is True and report["orphans"] == 1
    assert {pathlib.Path(s["file"]).name: s["reason"] for s in report["skipped"]} == {"manT.mdl": "orphaned-companion"}
    # A single input failed by --strict: the report says so (the command's exit code 1).
    one = sinew.convert(folder / "cube_mtllib_after_g.obj", tmp_path / "one.sinew", strict=True)
    assert one["failed"] == 1 and "--strict" in one["files"][0]["error"]
    assert not (tmp_path / "one.sinew").exists()
    first = sinew.convert(folder / "triangle.smd", tmp_path / "c.sinew", incremental=True)
    again = sinew.convert(folder / "triangle.smd", tmp_path / "c.sinew", incremental=True)
    assert (first["converted"], again["reused"]) == (1, 1)
    assert again["incremental"]["state"] == "used"
    alone = tmp_path / "alone"
    alone.mkdir()
    shutil.copy(corpus_dir / "mdl/man.mdl", alone / "man.mdl")
    with pytest.raises(sinew.InputError) as e:
        sinew.convert(alone / "man.mdl", tmp_path / "m.sinew")
    assert "man.mdl: textures at byte 180" in str(e.value) and "manT.mdl" in str(e.value)
    assert sinew.convert(alone / "man.mdl", tmp_path / "m.sinew", allow_missing=True)["converted"] == 1
