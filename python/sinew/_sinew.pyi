"""Type stubs of the extension module (Rust, PyO3). Use the functions of ``sinew`` instead."""

from typing import Any, Dict, List, Optional, Tuple, final

import numpy as np

__all__ = ["run", "bake", "write_cache", "load", "AssetHandle", "SinewError", "InputError", "UsageError",
           "__version__"]

__version__: str

class SinewError(Exception):
    """An error from sinew; ``args[0]`` is its one-line message (FILE: section at offset: problem)."""

class InputError(SinewError):
    """Bad input: a missing, unreadable or corrupt file (the command line's exit code 2)."""

class UsageError(SinewError):
    """Bad arguments: an unknown option or a value out of range (the command line's exit code 2)."""

def run(argv: List[str]) -> Tuple[int, Optional[str], Optional[str], bool]:
    """Runs a command as ``sinew --json``: (exit code, JSON report, error line, arguments refused)."""

def bake(path: str, clips: List[str] = ..., fps: Optional[float] = ..., mesh: Optional[int] = ..., lod: int = ...
         ) -> Tuple[bytes, int, int, float, str]:
    """In-memory bake: (little-endian f32 positions, frames, vertices, fps, clip ranges as JSON)."""

def write_cache(path: str, format: str, positions: bytes, frames: int, vertices: int, fps: float) -> None:
    """Writes a PC2 or MDD cache atomically."""

def load(path: str, lods: bool = ..., ms3d_position_keys: Optional[str] = ..., gltf_skin: Optional[int] = ...,
         allow_missing: bool = ...) -> Tuple[AssetHandle, Dict[str, Any]]:
    """Reads a file as the runtime sees it: (handle, the parts as a dict of read-only arrays)."""

@final
class AssetHandle:
    """A decoded asset held by Rust, for sampling and skinning. Use ``sinew.Asset`` instead."""

    def clip_index(self, clip: Any) -> int:
        """The index of a clip given by name (str) or index (int)."""
    def mesh_index(self, mesh: Any) -> int:
        """The index of a mesh given by name (str) or index (int)."""
    def joint_count(self) -> int:
        """Joints of the skeleton (UsageError when there is none)."""
    def skinned_vertex_count(self, mesh: int, lod: int) -> int:
        """Vertices of a skinned LOD."""
    def frame_times(self, clip: int, fps: Optional[float] = ...) -> np.ndarray:
        """The frame times ``sinew bake`` uses, float32 seconds."""
    def sample_into(self, clip: int, times: np.ndarray, local: bool, wrap: bool, out: np.ndarray) -> None:
        """Matrices (T, J, 4, 4) into ``out``."""
    def sample_trs_into(self, clip: int, times: np.ndarray, local: bool, wrap: bool, translations: np.ndarray,
                        rotations: np.ndarray, scales: np.ndarray) -> None:
        """Translations (T, J, 3), rotations (T, J, 4), scales (T, J, 3) into the arrays."""
    def skin_into(self, clip: int, times: np.ndarray, mesh: int, lod: int, wrap: bool, out: np.ndarray) -> None:
        """Positions (T, V, 3) into ``out``."""
