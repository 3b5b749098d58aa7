"""Batches past one machine: ``convert_many`` runs one ``sinew convert`` task per model on a Dask
cluster (``dask.distributed``), largest inputs first.

Each task converts one file where its worker runs and writes its output atomically there (shared
storage between the machines is the caller's, see docs/scale.md). A failing file fails its own entry
only. The result has one entry per input, in input order, with the fields of the command line's batch
report (``input``, ``output``, ``status``, ``error``, ``warnings`` and, when converted or reused, what
was written); the bytes are those a local ``sinew convert`` writes for the same options. The
command line's switches work the same: ``strict=True`` fails an input with a warning (nothing written
for it), ``allow_missing=True`` converts Half-Life models without their missing files, and
``incremental=True`` keeps the outputs whose files and options are unchanged (status ``reused``; one
record per output under ``out_dir/.sinew-incremental/``, so tasks never share a record file).
:func:`summary` gives the batch report's summary fields over the entries.
"""

from __future__ import annotations

import os
import uuid
from typing import Any, Iterable, List, Optional

from . import _options, _sinew

__all__ = ["convert_many", "plan", "summary"]


def plan(paths: Iterable[Any], out_dir: Any) -> List[tuple]:
    """``(input, output)`` pairs as ``sinew convert PATHS --out-dir OUT_DIR`` names them: a file
    becomes ``OUT_DIR/<stem>.sinew`` (``<file name>.sinew`` when stems collide)."""
    paths = [os.fspath(p) for p in paths]
    stems: dict = {}
    for p in paths:
        stem = os.path.splitext(os.path.basename(p))[0]
        stems[stem] = stems.get(stem, 0) + 1
    out = []
    for p in paths:
        base = os.path.basename(p)
        stem = os.path.splitext(base)[0]
        name = (base if stems[stem] > 1 else stem) + ".sinew"
        out.append((p, os.path.join(os.fspath(out_dir), name)))
    return out


def _convert_task(src: str, out: str, args: List[str]) -> dict:
    """One task: ``sinew convert SRC -o OUT ARGS`` on the worker; never raises for a bad file."""
    parent = os.path.dirname(out)
    if parent:
        os.makedirs(parent, exist_ok=True)
    crash_marker = os.environ.get("SINEW_TEST_CRASH_ONCE")
    if crash_marker and os.path.basename(src) in os.environ.get("SINEW_TEST_CRASH_FILE", ""):
        # Test hook (python/tests): the first attempt kills its worker process, to show that Dask
        # runs the task again elsewhere.
        try:
            fd = os.open(crash_marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            os.close(fd)
            os._exit(3)
        except FileExistsError:
            pass
    code, report, error, _ = _sinew.run(["convert", src, "-o", out, *args])
    if code in (0, 1) and report:
        # 1: failed by --strict, with its entry (status, error, warnings, diagnostics).
        import json

        return json.loads(report)["files"][0]
    return {"input": src, "output": out, "status": "failed", "error": error or "failed", "warnings": 0}


def convert_many(paths: Iterable[Any], out_dir: Any, client: Optional[Any] = None,
                 progress: bool = False, retries: int = 2, **options: Any) -> List[dict]:
    """Converts every file of ``paths`` into ``out_dir`` on a Dask cluster.

    ``client``: a ``dask.distributed.Client``; without one a ``LocalCluster`` is started for the call
    and closed after it. Tasks are submitted largest input first, one per file; a worker that dies
    has its task run again (``retries`` more times for tasks that raise). ``progress=True`` shows
    Dask's own progress bar (notebooks and terminals). ``options`` are ``convert``'s (see
    :func:`sinew.convert`). Returns one dict per input, in input order.
    """
    from dask.distributed import Client, LocalCluster

    pairs = plan(paths, out_dir)
    args = _options(options)
    own = client is None
    cluster = None
    if own:
        cluster = LocalCluster(processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        def size(p: str) -> int:
            try:
                return os.path.getsize(p)
            except OSError:
                return 0

        order = sorted(range(len(pairs)), key=lambda i: (-size(pairs[i][0]), i))
        futures = {}
        # Keys unique to this call: a key the cluster still holds from an earlier call would hand
        # back that call's result instead of running the task.
        call = uuid.uuid4().hex[:12]
        for i in order:
            src, out = pairs[i]
            futures[i] = client.submit(_convert_task, src, out, args,
                                       key=f"sinew-convert-{call}-{i}-{os.path.basename(src)}",
                                       pure=False, retries=retries)
        if progress:
            from dask.distributed import progress as show_progress

            show_progress(list(futures.values()))
        results = client.gather([futures[i] for i in range(len(pairs))], errors="skip")
        gathered = {}
        done = [futures[i] for i in range(len(pairs))]
        for i, f in enumerate(done):
            if f.status == "finished":
                gathered[i] = f.result()
            else:
                src, out = pairs[i]
                gathered[i] = {"input": src, "output": out, "status": "failed",
                               "error": f"{src}: the task failed on the cluster ({f.status})", "warnings": 0}
        del results
        return [gathered[i] for i in range(len(pairs))]
    finally:
        if own:
            client.close()
            if cluster is not None:
                cluster.close()


def summary(entries: Iterable[dict]) -> dict:
    """The summary fields of ``sinew convert --json`` (``inputs``, ``converted``, ``reused``,
    ``failed``, ``warnings``, ``inputs_with_warnings``, ``warning_codes``) over the entries
    :func:`convert_many` returned, counted as the command line counts them."""
    entries = list(entries)
    codes: dict = {}
    for e in entries:
        for d in e.get("diagnostics", []):
            if d.get("level") == "warning":
                codes[d["code"]] = codes.get(d["code"], 0) + 1
    count = lambda status: sum(1 for e in entries if e["status"] == status)  # noqa: E731
    return {
        "inputs": len(entries),
        "converted": count("converted"),
        "reused": count("reused"),
        "failed": count("failed"),
        "warnings": sum(e.get("warnings", 0) for e in entries),
        "inputs_with_warnings": sum(1 for e in entries if e.get("warnings", 0) > 0),
        "warning_codes": dict(sorted(codes.items())),
    }
