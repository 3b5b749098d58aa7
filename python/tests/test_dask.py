"""convert_many on a real LocalCluster of several worker processes: results like the command line's
batch, byte-identical outputs, a bad file reported alone, a killed worker's task run again."""

import os
import subprocess

import pytest

import sinew
from sinew.dask import convert_many, plan

distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def client(tmp_path_factory):
    marker = tmp_path_factory.mktemp("crash") / "crashed-once"
    # Read by sinew.dask's test hook in the worker processes, which inherit the environment.
    os.environ["SINEW_TEST_CRASH_ONCE"] = str(marker)
    os.environ["SINEW_TEST_CRASH_FILE"] = "zombie.ms3d"
    cluster = distributed.LocalCluster(n_workers=3, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    c = distributed.Client(cluster)
    yield c, marker
    c.close()
    cluster.close()
    del os.environ["SINEW_TEST_CRASH_ONCE"]
    del os.environ["SINEW_TEST_CRASH_FILE"]


def inputs(corpus):
    return [corpus / "gltf/CesiumMan.glb", corpus / "ms3d/zombie.ms3d", corpus / "ms3d/cross.ms3d",
            corpus / "mdl/man.mdl", corpus / "bvh/cmu_walk_crlf.bvh", corpus / "obj/spot.obj",
            corpus / "ms3d/malformed/Wuson_crlf_damaged.ms3d", corpus / "gltf/Fox.glb"]


def test_convert_many_matches_the_command_line_batch(client, corpus_dir, sinew_bin, tmp_path):
    c, marker = client
    files = inputs(corpus_dir)
    results = convert_many(files, tmp_path / "dask", client=c, lod="0.5")
    assert [r["input"] for r in results] == [str(f) for f in files]
    statuses = [r["status"] for r in results]
    assert statuses == ["converted"] * 6 + ["failed", "converted"]
    assert "at byte 300624" in results[6]["error"]
    # The task for zombie.ms3d killed its first worker; it ran again and converted.
    assert marker.exists()
    assert results[1]["status"] == "converted"

    # The command line's batch over the same files: same entries, same bytes.
    r = subprocess.run([str(sinew_bin), "--json", "convert", *map(str, files), "--out-dir", str(tmp_path / "cli"),
                        "--lod", "0.5"], capture_output=True, text=True)
    assert r.returncode == 1
    import json

    cli = json.loads(r.stdout)["files"]
    for mine, theirs in zip(results, cli):
        assert mine["status"] == theirs["status"]
        assert set(mine) == set(theirs), (set(mine) ^ set(theirs))
        if mine["status"] == "converted":
            a, b = open(mine["output"], "rb").read(), open(theirs["output"], "rb").read()
            assert a == b, mine["input"]
            for key in ["bytes", "format", "joints", "meshes", "clips"]:
                assert mine[key] == theirs[key]
        else:
            assert mine["error"] == theirs["error"]


def test_plan_names_outputs_as_the_command_line_does(tmp_path):
    pairs = plan(["a/x.glb", "b/x.obj", "c/y.ms3d"], tmp_path)
    assert [os.path.basename(o) for _, o in pairs] == ["x.glb.sinew", "x.obj.sinew", "y.sinew"]


def test_convert_many_takes_the_command_lines_switches_and_reports_the_same(client, corpus_dir, sinew_bin, tmp_path):
    import json
    import shutil

    from sinew.dask import summary

    c, _ = client
    # cube_mtllib_after_g.obj has warnings (its material library is not there); the others none.
    files = [corpus_dir / "obj/cube_mtllib_after_g.obj", corpus_dir / "smd/holy_grailref.smd",
             corpus_dir / "smd/triangle.smd"]
    strict = convert_many(files, tmp_path / "strict", client=c, strict=True, lod="none")
    r = subprocess.run([str(sinew_bin), "--json", "convert", *map(str, files), "--out-dir", str(tmp_path / "cli"),
                        "--strict", "--lod", "none"], capture_output=True, text=True)
    assert r.returncode == 1
    cli = json.loads(r.stdout)
    assert [e["status"] for e in strict] == ["failed", "converted", "converted"]
    assert [e["status"] for e in strict] == [e["status"] for e in cli["files"]]
    assert strict[0]["error"] == cli["files"][0]["error"] and "--strict" in strict[0]["error"]
    assert strict[0]["warnings"] == cli["files"][0]["warnings"] > 0
    assert not (tmp_path / "strict" / "cube_mtllib_after_g.sinew").exists()
    assert summary(strict) == {k: cli[k] for k in summary(strict)}

    # incremental: the second run reuses every output, the same entries but the status.
    first = convert_many(files, tmp_path / "inc", client=c, incremental=True, lod="none")
    again = convert_many(files, tmp_path / "inc", client=c, incremental=True, lod="none")
    assert [e["status"] for e in first] == ["converted"] * 3
    assert [e["status"] for e in again] == ["reused"] * 3
    for a, b in zip(first, again):
        assert {k: v for k, v in a.items() if k != "status"} == {k: v for k, v in b.items() if k != "status"}
    assert (tmp_path / "inc" / ".sinew-incremental" / "triangle.sinew.json").is_file()

    # allow_missing: man.mdl without its texture file fails, and converts when allowed.
    alone = tmp_path / "alone"
    alone.mkdir()
    shutil.copy(corpus_dir / "mdl/man.mdl", alone / "man.mdl")
    [refused] = convert_many([alone / "man.mdl"], tmp_path / "hl", client=c)
    assert refused["status"] == "failed" and "manT.mdl" in refused["error"]
    [allowed] = convert_many([alone / "man.mdl"], tmp_path / "hl", client=c, allow_missing=True)
    assert allowed["status"] == "converted"
    assert [d["code"] for d in allowed["diagnostics"] if d["level"] == "warning"] == ["mdl-missing-textures"]
