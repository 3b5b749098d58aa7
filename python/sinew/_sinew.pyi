"""Type stubs of the extension module (Rust, PyO3). Use the functions of ``sinew`` instead."""

from typing import List, Optional, Tuple

__version__: str

class SinewError(Exception):
    """An error from sinew; ``args[0]`` is its one-line message (FILE: section at offset: problem)."""

class InputError(SinewError):
    """Bad input: a missing, unreadable or corrupt file (the command line's exit code 2)."""

class UsageError(SinewError):
    """Bad arguments: an unknown option or a value out of range (the command line's exit code 2)."""

def run(argv: List[str]) -> Tuple[int, Optional[str], Optional[str], bool]:
    """Runs a command as ``sinew --json``: (exit code, JSON report, error line, arguments refused)."""

def bake(path: str, clips: List[str] = ..., fps: Optional[float] = ..., mesh: int = ..., lod: int = ...
         ) -> Tuple[bytes, int, int, float, str]:
    """In-memory bake: (little-endian f32 positions, frames, vertices, fps, clip ranges as JSON)."""

def write_cache(path: str, format: str, positions: bytes, frames: int, vertices: int, fps: float) -> None:
    """Writes a PC2 or MDD cache atomically."""
