"""Check that Blender plays a sinew vertex cache (PC2 or MDD) back as baked.

Run with Blender (tested with Debian's Blender 3.4.1):

    blender -b --factory-startup --python tools/blender_check_cache.py -- OBJ CACHE [options]

OBJ is the mesh written beside the cache by `sinew bake` (CACHE.obj), CACHE the .pc2 or .mdd file.
The script imports the OBJ with File > Import > Wavefront (the `wm.obj_import` operator of Blender
3.2+, or the legacy `import_scene.obj` with --legacy-importer), adds a Mesh Cache modifier as
docs/pipeline.md says (Format from the extension, Time Mode Frame, Play Mode Scene, Frame Start 0,
and the modifier's default axes Forward +Y, Up +Z unless --forward/--up are given), then evaluates
every frame of the cache and compares the evaluated mesh with the cache:

- in object space: the evaluated vertex coordinates against the cache's values (bit for bit when
  the importer keeps the file's coordinates in the mesh, as `wm.obj_import` does);
- in world space: the evaluated vertices through the object's matrix against the cache's values
  through the same map that takes the OBJ's own coordinates to the imported rest mesh (an affine
  least-squares fit over the rest vertices, so the check is meaningful for any importer and any axis
  settings). Plain Python only: Debian's Blender runs the system Python, without numpy.

It prints one line per frame with a difference and a summary, and exits 0 when the largest world-space
difference is at most --tolerance (default 1e-5) times the rest mesh's diagonal, 1 otherwise, 2 on
bad input. Outside Blender, `python3 tools/blender_check_cache.py --read-only OBJ CACHE` only reads the
two files and prints their counts (the test suite uses this; it does not need Blender).
"""

import argparse
import struct
import sys


def read_obj_vertices(path):
    """The `v` lines of an OBJ, in order, as (x, y, z) floats."""
    out = []
    with open(path, "r", encoding="utf-8") as f:
        for line in f:
            if line.startswith("v "):
                x, y, z = line.split()[1:4]
                out.append((float(x), float(y), float(z)))
    return out


def read_cache(path):
    """(kind, frames) of a PC2 (little-endian) or MDD (big-endian) file; frames are lists of (x, y, z)."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:12] == b"POINTCACHE2\0":
        version, points, _start, _rate, samples = struct.unpack_from("<iiffi", data, 12)
        if version != 1:
            raise ValueError(f"{path}: PC2 version {version}, expected 1")
        base, order, kind = 32, "<", "PC2"
    else:
        if len(data) < 8:
            raise ValueError(f"{path}: too short for PC2 or MDD")
        samples, points = struct.unpack_from(">ii", data, 0)
        base, order, kind = 8 + 4 * samples, ">", "MDD"
    if samples < 0 or points < 0 or len(data) != base + samples * points * 12:
        raise ValueError(f"{path}: {len(data)} bytes do not hold {samples} x {points} points")
    frames = []
    for s in range(samples):
        at = base + s * points * 12
        flat = struct.unpack_from(f"{order}{points * 3}f", data, at)
        frames.append([tuple(flat[i : i + 3]) for i in range(0, len(flat), 3)])
    return kind, frames


def solve(a, b):
    """Solves the small dense system a x = b by Gaussian elimination with partial pivoting."""
    n = len(a)
    m = [row[:] + [b[i]] for i, row in enumerate(a)]
    for c in range(n):
        p = max(range(c, n), key=lambda r: abs(m[r][c]))
        m[c], m[p] = m[p], m[c]
        if m[c][c] == 0.0:
            raise ValueError("degenerate rest mesh: cannot fit the file-to-world map")
        for r in range(n):
            if r != c:
                f = m[r][c] / m[c][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [m[i][n] / m[i][i] for i in range(n)]


def fit_affine(src, dst):
    """Least-squares affine map (x, y, z) -> M (x, y, z, 1) taking src points to dst points, as
    three rows of four numbers (plain Python: Debian's Blender has no numpy)."""
    ata = [[0.0] * 4 for _ in range(4)]
    atb = [[0.0] * 4 for _ in range(3)]
    for p, q in zip(src, dst):
        h = (p[0], p[1], p[2], 1.0)
        for i in range(4):
            for j in range(4):
                ata[i][j] += h[i] * h[j]
            for k in range(3):
                atb[k][i] += h[i] * q[k]
    return [solve(ata, atb[k]) for k in range(3)]


def apply_affine(m, p):
    return tuple(m[k][0] * p[0] + m[k][1] * p[1] + m[k][2] * p[2] + m[k][3] for k in range(3))


def distance(a, b):
    return sum((x - y) ** 2 for x, y in zip(a, b)) ** 0.5


def parse_args(argv):
    p = argparse.ArgumentParser(prog="blender_check_cache.py")
    p.add_argument("obj")
    p.add_argument("cache")
    p.add_argument("--forward", default="POS_Y", help="Mesh Cache forward axis (default POS_Y)")
    p.add_argument("--up", default="POS_Z", help="Mesh Cache up axis (default POS_Z)")
    p.add_argument("--legacy-importer", action="store_true", help="use import_scene.obj")
    p.add_argument("--tolerance", type=float, default=1e-5, help="relative to the rest diagonal")
    p.add_argument("--read-only", action="store_true", help="only read the files (no Blender)")
    return p.parse_args(argv)


def check_in_blender(args, obj_vertices, kind, frames):
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    if args.legacy_importer or not hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.import_scene.obj(filepath=args.obj, split_mode="OFF")
        importer = "import_scene.obj (legacy)"
    else:
        bpy.ops.wm.obj_import(filepath=args.obj)
        importer = "wm.obj_import"
    objects = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if len(objects) != 1:
        print(f"expected one mesh object from {args.obj}, got {len(objects)}", file=sys.stderr)
        return 2
    ob = objects[0]
    if len(ob.data.vertices) != len(obj_vertices):
        print(
            f"the importer made {len(ob.data.vertices)} vertices of the OBJ's {len(obj_vertices)}",
            file=sys.stderr,
        )
        return 2
    world = ob.matrix_world.copy()

    def world_of(co):
        return tuple(world @ co)

    rest_world = [world_of(v.co) for v in ob.data.vertices]
    file_to_world = fit_affine(obj_vertices, rest_world)
    lo = [min(p[k] for p in rest_world) for k in range(3)]
    hi = [max(p[k] for p in rest_world) for k in range(3)]
    diagonal = distance(lo, hi) or 1.0

    mod = ob.modifiers.new("cache", "MESH_CACHE")
    mod.cache_format = kind
    mod.filepath = args.cache
    mod.time_mode = "FRAME"
    mod.play_mode = "SCENE"
    mod.frame_start = 0.0
    mod.frame_scale = 1.0
    mod.forward_axis = args.forward
    mod.up_axis = args.up
    scene = bpy.context.scene
    print(
        f"Blender {bpy.app.version_string}, importer {importer}, {kind} {args.cache}: "
        f"{len(frames)} frames x {len(obj_vertices)} vertices, modifier axes forward {args.forward} "
        f"up {args.up}; object rotation (rad) {tuple(round(a, 6) for a in ob.rotation_euler)}"
    )
    worst, worst_local, exact_frames = 0.0, 0.0, 0
    for f, cache in enumerate(frames):
        scene.frame_set(f)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        evaluated = ob.evaluated_get(depsgraph)
        mesh = evaluated.to_mesh()
        d_world, d_local = 0.0, 0.0
        for v, want in zip(mesh.vertices, cache):
            d_local = max(d_local, max(abs(a - b) for a, b in zip(v.co, want)))
            d_world = max(d_world, distance(world_of(v.co), apply_affine(file_to_world, want)))
        evaluated.to_mesh_clear()
        worst, worst_local = max(worst, d_world), max(worst_local, d_local)
        if d_local == 0.0:
            exact_frames += 1
        if d_world > args.tolerance * diagonal:
            print(f"  frame {f}: world-space difference {d_world:.6g} ({d_world / diagonal:.3%} of the diagonal)")
    ok = worst <= args.tolerance * diagonal
    print(
        f"{'OK' if ok else 'DIFFERENT'}: largest world-space difference {worst:.6g} "
        f"({worst / diagonal:.3e} of the diagonal {diagonal:.6g}); object-space coordinates equal "
        f"the cache bit for bit in {exact_frames} of {len(frames)} frames (largest {worst_local:.6g})"
    )
    return 0 if ok else 1


def main():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
    args = parse_args(argv)
    try:
        obj_vertices = read_obj_vertices(args.obj)
        kind, frames = read_cache(args.cache)
    except (OSError, ValueError) as e:
        print(f"blender_check_cache: {e}", file=sys.stderr)
        return 2
    if frames and len(frames[0]) != len(obj_vertices):
        print(
            f"blender_check_cache: {args.cache} has {len(frames[0])} points, "
            f"{args.obj} {len(obj_vertices)} vertices",
            file=sys.stderr,
        )
        return 2
    if args.read_only:
        first = frames[0][0] if frames and frames[0] else None
        print(f"{kind} {len(frames)} frames x {len(obj_vertices)} vertices; first point {first}")
        return 0
    return check_in_blender(args, obj_vertices, kind, frames)


if __name__ == "__main__":
    sys.exit(main())
