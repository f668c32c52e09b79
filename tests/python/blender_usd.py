"""Imports a perifrac USD cache into Blender (5.x as the `bpy` module, or 4.x) and prints, for
every frame, the faces, the crack faces (the imported `crack` face attribute) and the vertices
of the mesh Blender's Mesh Sequence Cache gives, one line per frame:

    python3 tests/python/blender_usd.py CACHE.usda FRAMES

    frame K: F faces, C crack, V vertices, materials outside crack
"""

import sys

import bpy

path, frames = sys.argv[1], int(sys.argv[2])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.wm.usd_import(filepath=path)
scene = bpy.context.scene
obj = bpy.data.objects["surface"]
print("modifiers", " ".join(m.type for m in obj.modifiers))
for k in range(frames):
    scene.frame_set(k)
    mesh = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
    crack = mesh.attributes.get("crack")
    velocity = mesh.attributes.get("velocity")
    cracked = sum(1 for v in crack.data if v.value) if crack else -1
    print(
        f"frame {k}: {len(mesh.polygons)} faces, {cracked} crack, {len(mesh.vertices)} vertices,"
        f" velocity {'yes' if velocity else 'no'},"
        f" materials {' '.join(m.name for m in mesh.materials if m)}"
    )
