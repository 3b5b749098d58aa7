"""What Blender shows of a glTF file: import it with File > Import > glTF 2.0 and print, as JSON on the
last line of stdout, every mesh object (name, vertex count, world-space bounding box of its evaluated
mesh in the rest pose), the armatures and the actions.

Run with Blender (tested with Debian's Blender 3.4.1):

    blender -b --factory-startup --python tools/blender_gltf_check.py -- FILE.glb

Debian's Blender 3.4 runs the system Python, whose numpy (1.24+) no longer has `numpy.bool`, which
that version's glTF importer uses: the script sets `numpy.bool = bool` before importing (a packaging
fault of that Blender build, not of the file). Used for docs/export.md; the test suite does not need
Blender.
"""

import json
import sys

import bpy

try:
    import numpy

    if not hasattr(numpy, "bool"):
        numpy.bool = bool
except ImportError:
    pass


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 1:
        print("usage: blender -b --factory-startup --python blender_gltf_check.py -- FILE.glb",
              file=sys.stderr)
        sys.exit(2)
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    bpy.ops.import_scene.gltf(filepath=argv[0])
    depsgraph = bpy.context.evaluated_depsgraph_get()
    meshes = []
    for obj in sorted(bpy.data.objects, key=lambda o: o.name):
        if obj.type != "MESH":
            continue
        ev = obj.evaluated_get(depsgraph)
        mesh = ev.to_mesh()
        pts = [ev.matrix_world @ v.co for v in mesh.vertices]
        lo = [min(p[i] for p in pts) for i in range(3)] if pts else [0, 0, 0]
        hi = [max(p[i] for p in pts) for i in range(3)] if pts else [0, 0, 0]
        meshes.append({
            "name": obj.name,
            "vertices": len(mesh.vertices),
            "min": [round(x, 4) for x in lo],
            "max": [round(x, 4) for x in hi],
            "visible": obj.visible_get(),
        })
        ev.to_mesh_clear()
    report = {
        "meshes": meshes,
        "armatures": sorted(o.name for o in bpy.data.objects if o.type == "ARMATURE"),
        "actions": len(bpy.data.actions),
        "images": len(bpy.data.images),
    }
    print(json.dumps(report))


main()
