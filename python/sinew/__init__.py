"""sinew from Python: the command line's functions as calls that return Python data.

Every function runs the same code as the ``sinew`` binary (same options, checks, outputs and
report), with the GIL released while sinew works:

- ``inspect(path)`` -> dict, the schema of ``sinew inspect --json`` (docs/cli.md);
- ``convert(src, out=None, out_dir=None, **options)`` -> dict, the report of ``sinew convert --json``;
- ``bake(src, clip=None, fps=None)`` -> ``numpy.ndarray`` of shape (frames, vertices, 3), float32;
- ``write_pc2(path, positions, fps)``, ``write_mdd(path, positions, fps)``: the cache writers;
- ``bake_to(src, out, format="pc2", **options)`` -> dict: ``sinew bake`` (EXR, PC2, MDD, sidecar, OBJ);
- ``verify(cache, against)`` -> dict, the report of ``sinew verify --json`` (``identical`` says it all);
- ``map(rig, motion, **options)`` -> dict, the report of ``sinew map --json``;
- ``load(path)`` -> :class:`Asset`: the file as numpy arrays (skeleton, clips, meshes, masks, game
  data), with ``asset.sample(clip, times)`` -> ``(T, J, 4, 4)`` joint matrices and
  ``asset.skin(clip, times)`` -> ``(T, V, 3)`` positions from sinew's runtime (``sinew.asset``).

Options are the command line's, spelled with underscores: ``convert(src, out, lod="none",
no_compress=True, anim=["walk.bvh", "run.bvh"])`` is ``sinew convert src -o out --lod none
--no-compress --anim walk.bvh --anim run.bvh``. ``True`` gives a flag, ``False`` and ``None`` leave
the option out, a list repeats it.

Errors raise :class:`SinewError` subclasses carrying the command line's one-line message (file,
section, byte offset or line, problem): :class:`InputError` for a bad or missing file,
:class:`UsageError` for bad options. ``sinew.dask.convert_many`` spreads a batch over a Dask cluster.
"""

from __future__ import annotations

import json
import os
from typing import Any, Iterable, Optional, Sequence, Union

import numpy as np

from . import _sinew
from ._sinew import InputError, SinewError, UsageError
from .asset import Asset, Clip, Lod, Mask, Material, Mesh, Skeleton, load

__all__ = [
    "SinewError",
    "InputError",
    "UsageError",
    "inspect",
    "convert",
    "bake",
    "bake_to",
    "write_pc2",
    "write_mdd",
    "verify",
    "map",
    "export",
    "preview",
    "run",
    "load",
    "Asset",
    "Skeleton",
    "Clip",
    "Mesh",
    "Lod",
    "Material",
    "Mask",
    "__version__",
]

__version__: str = _sinew.__version__

PathLike = Union[str, "os.PathLike[str]"]


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _options(options: dict) -> list:
    """Command-line arguments for keyword options (sorted by name, so the argument list is stable)."""
    out: list = []
    for name in sorted(options):
        value = options[name]
        if value is None or value is False:
            continue
        if value is True:
            out.append(_flag(name))
        elif isinstance(value, (list, tuple)):
            for v in value:
                out += [_flag(name), os.fspath(v) if isinstance(v, os.PathLike) else str(v)]
        else:
            out += [_flag(name), os.fspath(value) if isinstance(value, os.PathLike) else str(value)]
    return out


def run(args: Sequence[str]) -> tuple:
    """Runs a ``sinew`` command (arguments without the program name) with ``--json``.

    Returns ``(exit_code, report)``: 0 success, 1 a check failed or a file of a batch failed (the
    report says which). Exit code 2 raises :class:`UsageError` (bad arguments) or
    :class:`InputError` (bad input), with the command line's message.
    """
    code, report, error, usage = _sinew.run([os.fspath(a) for a in args])
    if code == 2:
        raise (UsageError if usage else InputError)(error or "failed")
    return code, (json.loads(report) if report is not None else None)


def inspect(path: PathLike, **options: Any) -> dict:
    """What a file holds: skeleton, clips, meshes, LODs, materials, game data, diagnostics.

    The dictionary has the schema of ``sinew inspect --json`` (docs/cli.md).
    """
    _, report = run(["inspect", os.fspath(path), *_options(options)])
    return report


def convert(src: Union[PathLike, Iterable[PathLike]], out: Optional[PathLike] = None,
            out_dir: Optional[PathLike] = None, **options: Any) -> dict:
    """Converts one file to ``out`` (``.sinew``), or files and folders into ``out_dir``.

    Returns the report of ``sinew convert --json``: ``inputs``, ``converted``, ``reused``,
    ``failed``, the warning summary (``warnings``, ``inputs_with_warnings``, ``warning_codes``),
    ``files`` (one entry per input with ``status``, ``error``, ``warnings`` and what was written) and
    ``skipped`` (what a folder walk passed over, with the reason). A single input that fails raises
    :class:`InputError`; in a batch (``out_dir``) failures are in the report. The command line's
    switches: ``strict=True`` fails an input with any warning (nothing written for it; the report
    says ``failed``, also for a single input, as the command's exit code 1 does),
    ``allow_missing=True`` converts a Half-Life model without its missing SMDs or companion files,
    ``incremental=True`` keeps outputs whose files, options and sinew version are unchanged
    (status ``reused``).
    """
    sources = [src] if isinstance(src, (str, os.PathLike)) else list(src)
    args = ["convert", *[os.fspath(s) for s in sources]]
    if out is not None:
        args += ["-o", os.fspath(out)]
    if out_dir is not None:
        args += ["--out-dir", os.fspath(out_dir)]
    _, report = run(args + _options(options))
    return report


def bake(src: PathLike, clip: Union[None, str, Sequence[str]] = None, fps: Optional[float] = None,
         mesh: Optional[int] = None, lod: int = 0) -> np.ndarray:
    """Skins a mesh through clips with sinew's runtime, in memory.

    Returns a float32 array of shape ``(frames, vertices, 3)``: the positions ``sinew bake`` writes
    (split vertex order) of ``mesh`` (default: the model's default body, its meshes one after another).
    ``clip`` is a name or a list baked one after another (default: every clip);
    ``fps`` defaults to the first clip's rate. The frame ranges of the clips are in the array's
    ``clips`` attribute of :func:`bake_frames`.
    """
    return bake_frames(src, clip=clip, fps=fps, mesh=mesh, lod=lod)[0]


def bake_frames(src: PathLike, clip: Union[None, str, Sequence[str]] = None,
                fps: Optional[float] = None, mesh: Optional[int] = None, lod: int = 0) -> tuple:
    """Like :func:`bake`, returning ``(positions, fps, clips)`` where ``clips`` lists
    ``{name, first_frame, frame_count, looping, duration}`` per clip baked."""
    clips = [] if clip is None else ([clip] if isinstance(clip, str) else list(clip))
    data, frames, vertices, rate, ranges = _sinew.bake(os.fspath(src), clips, fps, mesh, lod)
    positions = np.frombuffer(data, dtype="<f4").reshape(frames, vertices, 3).copy()
    return positions, rate, json.loads(ranges)


def _write_cache(path: PathLike, fmt: str, positions: Any, fps: float) -> None:
    array = np.ascontiguousarray(np.asarray(positions, dtype="<f4"))
    if array.ndim != 3 or array.shape[2] != 3:
        raise UsageError(f"{os.fspath(path)}: positions must have shape (frames, vertices, 3), not {array.shape}")
    frames, vertices, _ = array.shape
    _sinew.write_cache(os.fspath(path), fmt, array.tobytes(), frames, vertices, float(fps))


def write_pc2(path: PathLike, positions: Any, fps: float) -> None:
    """Writes a PC2 point cache (3ds Max / Blender Mesh Cache) atomically."""
    _write_cache(path, "pc2", positions, fps)


def write_mdd(path: PathLike, positions: Any, fps: float) -> None:
    """Writes an MDD point cache (LightWave, big-endian) atomically."""
    _write_cache(path, "mdd", positions, fps)


def bake_to(src: PathLike, out: PathLike, format: str = "pc2", **options: Any) -> dict:
    """Bakes a cache file as ``sinew bake`` does (``format``: ``exr``, ``pc2`` or ``mdd``), with its
    JSON sidecar and OBJ; returns the command's report."""
    _, report = run(["bake", os.fspath(src), "--format", format, "-o", os.fspath(out), *_options(options)])
    return report


def verify(cache: PathLike, against: PathLike, **options: Any) -> dict:
    """Checks a baked cache bit for bit against a re-bake through sinew's runtime.

    Returns the report of ``sinew verify --json``; ``report["identical"]`` is the answer.
    """
    _, report = run(["verify", os.fspath(cache), "--against", os.fspath(against), *_options(options)])
    return report


def map(rig: PathLike, motion: PathLike, **options: Any) -> dict:  # noqa: A001 - mirrors `sinew map`
    """How a motion's joints bind to a rig's joints: the report of ``sinew map --json``."""
    _, report = run(["map", os.fspath(rig), os.fspath(motion), *_options(options)])
    return report


def export(src: PathLike, out: PathLike, **options: Any) -> dict:
    """Writes ``src`` as glTF 2.0 (``out`` ending in ``.glb`` or ``.gltf``) as ``sinew export`` does;
    returns the command's report (docs/export.md)."""
    _, report = run(["export", os.fspath(src), "-o", os.fspath(out), *_options(options)])
    return report


def preview(src: PathLike, out: PathLike, **options: Any) -> dict:
    """Draws the contact sheet of ``src`` into the PNG ``out`` as ``sinew preview`` does (options such
    as ``clip="walk", frames=4, names=True``); returns the command's report."""
    _, report = run(["preview", os.fspath(src), "-o", os.fspath(out), *_options(options)])
    return report
