"""An asset as numpy data: ``sinew.load(path)``, and sampling and skinning at the runtime's speed.

:func:`load` reads any file sinew reads (MS3D, SMD/QC/MDL, glTF, OBJ, BVH) or a ``.sinew`` as the
runtime sees it (a source file is imported, compiled and read back, as ``sinew inspect --pose`` and
``sinew bake`` do) and returns an :class:`Asset`. Its parts are numpy arrays, each one read-only copy
made at load; names are tuples of ``str``. :meth:`Asset.sample` and :meth:`Asset.skin` run sinew's
runtime (Rust, through the extension module) on arrays of times, with the GIL released, into a new
array or a preallocated one.

Conventions:

- Units are the file's model units and seconds. Rotations are unit quaternions ``(x, y, z, w)``.
- A 4x4 matrix ``m`` is indexed ``m[row, col]``: it maps a point as ``m @ [x, y, z, 1]`` and its
  translation is ``m[:3, 3]`` (the runtime's column-major matrices, transposed into numpy's order;
  the numbers are the runtime's bits).
- Local transforms are relative to the parent joint; model-space ones are composed from the root.
- Times are ``float32`` seconds, converted from whatever array is given. By default every time must
  lie in ``[0, duration]``; ``wrap=True`` accepts any finite time and applies the runtime's rule
  (a looping clip's time wraps around, another's is clamped to its ends).

Nothing here computes a pose or a vertex: the extension module calls ``sinew_pipeline::pose`` and
``sinew_pipeline::bake`` on the decoded asset, the code behind ``inspect --pose`` and ``bake``.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from typing import Any, Dict, Optional, Tuple, Union

import numpy as np

from . import _sinew
from ._sinew import UsageError

__all__ = ["load", "Asset", "Skeleton", "Clip", "Mesh", "Lod", "Material", "Mask"]

PathLike = Union[str, "os.PathLike[str]"]


@dataclass(frozen=True, repr=False, eq=False)
class Skeleton:
    """Joints in runtime order (every parent before its children); ``J`` joints.

    Attributes:
        names: joint names, ``J`` strings.
        parents: ``(J,)`` int32, the parent's index, ``-1`` for a root.
        bind_translations: ``(J, 3)`` float32, bind-pose translation relative to the parent (model
            units).
        bind_rotations: ``(J, 4)`` float32, bind-pose rotation relative to the parent, ``(x, y, z, w)``.
        bind_scales: ``(J, 3)`` float32, bind-pose scale along the joint's own axes.
        bind_local: ``(J, 4, 4)`` float32, the bind pose's local matrices ``T * R * S``.
        bind_model: ``(J, 4, 4)`` float32, the bind pose in model space (the runtime's
            local-to-model of the bind pose).
        inverse_bind: ``(J, 4, 4)`` float32, the inverse bind matrices skinning uses (a glTF file's
            own, otherwise the inverse of the bind pose in model space).
    """

    names: Tuple[str, ...]
    parents: np.ndarray
    bind_translations: np.ndarray
    bind_rotations: np.ndarray
    bind_scales: np.ndarray
    bind_local: np.ndarray
    bind_model: np.ndarray
    inverse_bind: np.ndarray

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        """The index of the joint called ``name`` (``ValueError`` when there is none)."""
        return self.names.index(name)

    def __repr__(self) -> str:
        return f"Skeleton({len(self)} joints)"


@dataclass(frozen=True, repr=False, eq=False)
class Clip:
    """One clip as the runtime plays it.

    Attributes:
        name: clip name.
        duration: seconds.
        sample_rate: the source's frame rate, frames per second.
        looping: whether time wraps around at ``duration``.
        additive: whether the clip holds differences from a reference pose.
        compressed: whether the keys are stored quantized (a ``.sinew`` converted with compression).
        tracks: the joint names the clip's tracks drive, in track order (they may name joints the
            skeleton lacks: clips bind by name).
        driven: ``(K,)`` int32, the skeleton joints the clip drives, ascending.
        unbound: track names that match no skeleton joint.
        times: ``(N,)`` float32, the key times shared by every animated channel, seconds (``[0.0]``
            when every channel is constant: a clip holding one still pose).
    """

    name: str
    duration: float
    sample_rate: float
    looping: bool
    additive: bool
    compressed: bool
    tracks: Tuple[str, ...]
    driven: np.ndarray
    unbound: Tuple[str, ...]
    times: np.ndarray

    def __repr__(self) -> str:
        return (f"Clip({self.name!r}, {self.duration:g} s, {self.sample_rate:g} fps"
                f"{', looping' if self.looping else ''}, {len(self.tracks)} tracks)")


@dataclass(frozen=True, repr=False, eq=False)
class Lod:
    """One level of detail of a mesh: ``V`` vertices, ``F`` triangles, ``S`` submeshes.

    Attributes:
        positions: ``(V, 3)`` float32, bind-pose positions, model space.
        normals: ``(V, 3)`` float32 unit normals, or ``(0, 3)`` when the mesh has none.
        uvs: ``(V, 2)`` float32 texture coordinates, or ``(0, 2)``.
        indices: ``(F, 3)`` uint32, three vertex indices per triangle.
        joint_indices: ``(V, 4)`` uint16, up to four skeleton joints per vertex, or ``(0, 4)`` for a
            static mesh.
        joint_weights: ``(V, 4)`` float32, the matching weights (summing to one), or ``(0, 4)``.
        submeshes: ``(S, 2)`` uint32, ``[first index, index count]`` of each material range, counted
            in ``indices.reshape(-1)`` (three per triangle).
        materials: ``S`` material names, one per submesh (``""`` when the source gave none).
        error: simplification error relative to the mesh's extent (0 for LOD 0).
        target_ratio, reached_ratio: the fraction of LOD 0's triangles asked for and kept.
        error_model: simplification error in model units.
        source_vertex: LOD 0 only, when the file has it: ``(V,)`` uint32, the source file's vertex
            each vertex was split from; otherwise ``None``.
        source_vertex_count: the number of vertices in the source file, or ``None``.
    """

    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    indices: np.ndarray
    joint_indices: np.ndarray
    joint_weights: np.ndarray
    submeshes: np.ndarray
    materials: Tuple[str, ...]
    error: float
    target_ratio: float
    reached_ratio: float
    error_model: float
    source_vertex: Optional[np.ndarray]
    source_vertex_count: Optional[int]

    @property
    def skinned(self) -> bool:
        """Whether every vertex has joint weights."""
        return len(self.joint_indices) > 0

    def __repr__(self) -> str:
        return f"Lod({len(self.positions)} vertices, {len(self.indices)} triangles)"


@dataclass(frozen=True, repr=False, eq=False)
class Mesh:
    """A mesh and its LOD chain (LOD 0 is the source mesh)."""

    name: str
    lods: Tuple[Lod, ...]

    def __repr__(self) -> str:
        return f"Mesh({self.name!r}, {len(self.lods)} LODs)"


@dataclass(frozen=True, eq=False)
class Material:
    """A material: ``name``, ``base_color`` (``(4,)`` float32 linear RGBA) and ``texture`` (a path or
    URI, or ``None``)."""

    name: str
    base_color: np.ndarray
    texture: Optional[str]


@dataclass(frozen=True, eq=False)
class Mask:
    """A named per-joint weight mask (for masked blending).

    Attributes:
        name: mask name.
        joints: the joint names the mask lists.
        weights: ``(K,)`` float32, their weights.
        per_joint: ``(J,)`` float32, one weight per skeleton joint (0 for joints not listed), as the
            runtime applies it; ``(0,)`` when the file has no skeleton.
    """

    name: str
    joints: Tuple[str, ...]
    weights: np.ndarray
    per_joint: np.ndarray


ClipRef = Union[str, int]
MeshRef = Union[str, int]


def _times(times: Any) -> np.ndarray:
    t = np.ascontiguousarray(times, dtype=np.float32)
    if t.ndim == 0:
        t = t.reshape(1)
    if t.ndim != 1:
        raise UsageError(f"times must be a scalar or a 1-D array, not an array of shape {t.shape}")
    return t


def _out(out: Optional[np.ndarray], shape: Tuple[int, ...]) -> np.ndarray:
    return np.empty(shape, dtype=np.float32) if out is None else out


@dataclass(frozen=True, repr=False, eq=False)
class Asset:
    """A file as sinew's runtime holds it. Build one with :func:`load`.

    Attributes:
        path: the path as given.
        skeleton: the :class:`Skeleton`, or ``None`` (a static mesh).
        clips: the :class:`Clip` s, in file order.
        meshes: the :class:`Mesh` es, in file order.
        materials: the :class:`Material` s submeshes name.
        masks: the named joint :class:`Mask` s.
        game: Half-Life game data (attachments, hit boxes, controllers, body groups, skin families,
            per-clip activities and events...) with the schema of ``sinew inspect --json``'s ``game``
            field (docs/cli.md), or ``None``.
    """

    path: str
    skeleton: Optional[Skeleton]
    clips: Tuple[Clip, ...]
    meshes: Tuple[Mesh, ...]
    materials: Tuple[Material, ...]
    masks: Tuple[Mask, ...]
    game: Optional[Dict[str, Any]]
    _handle: _sinew.AssetHandle = field(compare=False)

    def __repr__(self) -> str:
        joints = len(self.skeleton) if self.skeleton is not None else 0
        return (f"Asset({self.path!r}: {joints} joints, {len(self.clips)} clips, "
                f"{len(self.meshes)} meshes)")

    def clip(self, clip: ClipRef) -> Clip:
        """The clip called ``clip`` (or at index ``clip``); :class:`UsageError` lists the names when
        there is none."""
        return self.clips[self._handle.clip_index(clip)]

    def frame_times(self, clip: ClipRef, fps: Optional[float] = None) -> np.ndarray:
        """The frame times ``sinew bake --clip`` uses (and ``sinew inspect --pose CLIP@0..DURATION``):
        ``(N,)`` float32 seconds at ``fps`` (default: the clip's sample rate), the last exactly the
        clip's duration. ``N = ceil(duration * fps - 0.001) + 1``."""
        return self._handle.frame_times(self._handle.clip_index(clip), fps)

    def sample(self, clip: ClipRef, times: Any, local: bool = False,
               out: Optional[np.ndarray] = None, wrap: bool = False) -> np.ndarray:
        """Poses ``clip`` at each time with sinew's runtime.

        Args:
            clip: a clip name or index.
            times: seconds, a scalar or any 1-D array (converted to float32); ``T`` times.
            local: ``False`` for model-space matrices (each joint composed with its parents, the
                numbers ``sinew inspect --pose`` prints), ``True`` for local ones (relative to the
                parent, as the runtime's sampler gives them).
            out: a preallocated C-contiguous float32 array of shape ``(T, J, 4, 4)`` to write into.
            wrap: accept times outside ``[0, duration]`` and apply the runtime's rule.

        Returns:
            ``(T, J, 4, 4)`` float32 matrices (``out`` when given), ``m[row, col]``, model units.

        The GIL is released while the runtime works.
        """
        t = _times(times)
        joints = self._handle.joint_count()
        index = self._handle.clip_index(clip)
        result = _out(out, (len(t), joints, 4, 4))
        self._handle.sample_into(index, t, bool(local), bool(wrap), result)
        return result

    def sample_trs(self, clip: ClipRef, times: Any, local: bool = True,
                   wrap: bool = False) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Poses ``clip`` at each time, as ``(translations, rotations, scales)``.

        Shapes ``(T, J, 3)``, ``(T, J, 4)`` (quaternions ``x, y, z, w``) and ``(T, J, 3)``, float32.
        ``local=True`` (the default) gives the runtime's local transforms themselves;
        ``local=False`` splits the model-space matrices as ``sinew inspect --pose`` does (its
        ``translation``, ``rotation`` and ``scale`` fields). The GIL is released while the runtime
        works.
        """
        t = _times(times)
        j = self._handle.joint_count()
        index = self._handle.clip_index(clip)
        tr = np.empty((len(t), j, 3), np.float32)
        ro = np.empty((len(t), j, 4), np.float32)
        sc = np.empty((len(t), j, 3), np.float32)
        self._handle.sample_trs_into(index, t, bool(local), bool(wrap), tr, ro, sc)
        return tr, ro, sc

    def skin(self, clip: ClipRef, times: Any, mesh: MeshRef = 0, lod: int = 0,
             out: Optional[np.ndarray] = None, wrap: bool = False) -> np.ndarray:
        """Skins a mesh through ``clip`` at each time with sinew's runtime.

        Args:
            clip: a clip name or index.
            times: seconds, a scalar or any 1-D array (converted to float32); ``T`` times.
            mesh: a mesh name or index.
            lod: the LOD index (``load(path, lods=True)`` generates LODs for a source without any,
                as ``sinew bake --lod`` does).
            out: a preallocated C-contiguous float32 array of shape ``(T, V, 3)`` to write into.
            wrap: accept times outside ``[0, duration]`` and apply the runtime's rule.

        Returns:
            ``(T, V, 3)`` float32 vertex positions, model units, in the LOD's own vertex order (the
            order of :attr:`Lod.positions`). At :meth:`frame_times` they are the bits
            ``sinew bake --clip`` writes.

        The GIL is released while the runtime works (frames are skinned in parallel).
        """
        t = _times(times)
        index = self._handle.clip_index(clip)
        m = self._handle.mesh_index(mesh)
        v = self._handle.skinned_vertex_count(m, int(lod))
        result = _out(out, (len(t), v, 3))
        self._handle.skin_into(index, t, m, int(lod), bool(wrap), result)
        return result


def _lod(d: Dict[str, Any]) -> Lod:
    return Lod(**d)


def load(path: PathLike, lods: bool = False, ms3d_position_keys: Optional[str] = None,
         gltf_skin: Optional[int] = None, allow_missing: bool = False) -> Asset:
    """Reads a file as sinew's runtime sees it and returns its :class:`Asset`.

    Args:
        path: any file sinew reads (``.ms3d .smd .qc .mdl .gltf .glb .obj .bvh``) or a ``.sinew``.
        lods: for a source file without LODs, generate them as ``sinew bake --lod`` does (slower).
        ms3d_position_keys: ``"auto"`` (default), ``"viewer"`` or ``"parent"``, as
            ``--ms3d-position-keys``.
        gltf_skin: the glTF skin that becomes the skeleton, as ``--gltf-skin``.
        allow_missing: Half-Life: load without a file the model names that is missing (a QC's SMD,
            an MDL's texture or sequence-group file), as ``--allow-missing``; by default that is an
            :class:`InputError`.

    Raises:
        InputError: a missing, unreadable or malformed file, with the command line's one-line
            message (file, section, offset or line).
    """
    handle, p = _sinew.load(os.fspath(path), bool(lods), ms3d_position_keys, gltf_skin,
                            bool(allow_missing))
    s = p["skeleton"]
    return Asset(
        path=p["path"],
        skeleton=Skeleton(**s) if s is not None else None,
        clips=tuple(Clip(**c) for c in p["clips"]),
        meshes=tuple(Mesh(name=m["name"], lods=tuple(_lod(l) for l in m["lods"])) for m in p["meshes"]),
        materials=tuple(Material(**m) for m in p["materials"]),
        masks=tuple(Mask(**m) for m in p["masks"]),
        game=json.loads(p["game"]) if p["game"] is not None else None,
        _handle=handle,
    )
