"""Import a perifrac run directory into Blender as an animation.

Blender's own PLY importer reads the surfaces but drops the per-face `crack` flag. This script
reads `run.json` and every `frames/surface_NNNN.ply`, makes one object per frame with two
materials ("perifrac surface", "perifrac crack") chosen per face by the flag, which it also keeps
as an integer face attribute `crack`, shows each object only on its own frame, and adds the
run's balls (keyed per frame) and ground planes. Units stay metres; perifrac's up axis
(`run.json` "up", +z unless gravity says otherwise) is kept as it is.

    blender --python tools/blender_import.py -- out/wall            # open Blender with it
    blender -b --python tools/blender_import.py -- out/wall --save out/wall/wall.blend
    blender -b --python tools/blender_import.py -- out/wall --frame 24 --report

Runs inside Blender (3.x or 4.x); needs nothing beyond Blender's Python.
"""

import json
import os
import struct
import sys

import bpy
from mathutils import Vector

SCALARS = {
    "char": "b", "int8": "b", "uchar": "B", "uint8": "B",
    "short": "h", "int16": "h", "ushort": "H", "uint16": "H",
    "int": "i", "int32": "i", "uint": "I", "uint32": "I",
    "float": "f", "float32": "f", "double": "d", "float64": "d",
}


def read_ply(path):
    """Vertices, faces and per-face crack flags (0 when absent) of a PLY surface."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").splitlines()
    fmt = None
    elements = []
    for line in header:
        words = line.split()
        if not words:
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            if words[1] == "list":
                elements[-1][2].append((words[4], "list", words[2], words[3]))
            else:
                elements[-1][2].append((words[2], words[1]))
    if fmt not in ("ascii", "binary_little_endian", "binary_big_endian"):
        raise ValueError(f"{path}: unknown PLY format {fmt}")
    body = data[end:]
    vertices, faces, crack = [], [], []
    if fmt == "ascii":
        tokens = iter(body.split())
        for name, count, props in elements:
            for _ in range(count):
                row = {}
                for p in props:
                    if p[1] == "list":
                        n = int(next(tokens))
                        row[p[0]] = [int(next(tokens)) for _ in range(n)]
                    else:
                        row[p[0]] = float(next(tokens))
                collect(name, row, vertices, faces, crack)
    else:
        order = "<" if fmt == "binary_little_endian" else ">"
        pos = 0
        for name, count, props in elements:
            for _ in range(count):
                row = {}
                for p in props:
                    if p[1] == "list":
                        cf = order + SCALARS[p[2]]
                        (n,) = struct.unpack_from(cf, body, pos)
                        pos += struct.calcsize(cf)
                        fmt_n = order + SCALARS[p[3]] * n
                        row[p[0]] = list(struct.unpack_from(fmt_n, body, pos))
                        pos += struct.calcsize(fmt_n)
                    else:
                        sf = order + SCALARS[p[1]]
                        (row[p[0]],) = struct.unpack_from(sf, body, pos)
                        pos += struct.calcsize(sf)
                collect(name, row, vertices, faces, crack)
    return vertices, faces, crack


def collect(element, row, vertices, faces, crack):
    if element == "vertex":
        vertices.append((row["x"], row["y"], row["z"]))
    elif element == "face":
        faces.append(row.get("vertex_indices") or row.get("vertex_index"))
        crack.append(int(row.get("crack", 0)))


def material(name, rgb):
    m = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    m.diffuse_color = (*rgb, 1.0)
    m.use_nodes = True
    bsdf = m.node_tree.nodes.get("Principled BSDF")
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    return m


def show_only_on(obj, frame, last):
    """Key the object visible on `frame` and hidden on the frames around it."""
    for f, hidden in ((frame - 1, True), (frame, False), (frame + 1, True)):
        if 0 <= f <= last:
            obj.hide_viewport = hidden
            obj.hide_render = hidden
            obj.keyframe_insert("hide_viewport", frame=f)
            obj.keyframe_insert("hide_render", frame=f)
    for curve in obj.animation_data.action.fcurves:
        for k in curve.keyframe_points:
            k.interpolation = "CONSTANT"


def import_run(run_dir, only=None):
    with open(os.path.join(run_dir, "run.json")) as f:
        run = json.load(f)
    frames = run["frames"]
    if only is not None:
        frames = [fr for fr in frames if fr["index"] == only]
        if not frames:
            raise ValueError(f"{run_dir}: no frame {only}")
    scene = bpy.context.scene
    scene.frame_start = 0
    scene.frame_end = run["frames"][-1]["index"]
    col = bpy.data.collections.new("perifrac " + run.get("scene", run_dir))
    scene.collection.children.link(col)
    surface_mat = material("perifrac surface", (0.8, 0.8, 0.78))
    crack_mat = material("perifrac crack", (0.95, 0.45, 0.1))
    report = []
    for fr in frames:
        vertices, faces, crack = read_ply(os.path.join(run_dir, fr["surface"]))
        mesh = bpy.data.meshes.new(f"frame_{fr['index']:04d}")
        mesh.from_pydata(vertices, [], faces)
        mesh.materials.append(surface_mat)
        mesh.materials.append(crack_mat)
        mesh.polygons.foreach_set("material_index", crack)
        attr = mesh.attributes.new("crack", "INT", "FACE")
        attr.data.foreach_set("value", crack)
        mesh.update()
        obj = bpy.data.objects.new(mesh.name, mesh)
        col.objects.link(obj)
        if only is None:
            show_only_on(obj, fr["index"], scene.frame_end)
        report.append((fr["index"], len(mesh.vertices), len(mesh.polygons), sum(crack)))
    balls = run["frames"][0].get("balls", [])
    for b, ball in enumerate(balls):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=ball["radius"], location=ball["center"])
        obj = bpy.context.active_object
        obj.name = f"ball_{b}"
        for c in list(obj.users_collection):
            c.objects.unlink(obj)
        col.objects.link(obj)
        for fr in run["frames"]:
            obj.location = fr["balls"][b]["center"]
            obj.keyframe_insert("location", frame=fr["index"])
    for g, ground in enumerate(run.get("grounds", [])):
        bpy.ops.mesh.primitive_plane_add(size=100.0, location=ground["point"])
        obj = bpy.context.active_object
        obj.name = f"ground_{g}"
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector((0.0, 0.0, 1.0)).rotation_difference(
            Vector(ground["normal"])
        )
        for c in list(obj.users_collection):
            c.objects.unlink(obj)
        col.objects.link(obj)
    return report


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not argv:
        raise SystemExit("usage: blender --python tools/blender_import.py -- RUN_DIR "
                         "[--frame N] [--save FILE.blend] [--report]")
    run_dir, only, save, report = argv[0], None, None, False
    rest = argv[1:]
    while rest:
        opt = rest.pop(0)
        if opt == "--frame":
            only = int(rest.pop(0))
        elif opt == "--save":
            save = rest.pop(0)
        elif opt == "--report":
            report = True
        else:
            raise SystemExit(f"unknown option {opt}")
    if bpy.app.background:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    rows = import_run(run_dir, only)
    if report:
        for index, nv, nf, nc in rows:
            print(f"perifrac frame {index}: {nv} vertices, {nf} faces, {nc} crack faces")
    if save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(save))


if __name__ == "__main__":
    main()
