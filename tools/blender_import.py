"""Import a perifrac run directory into Blender as an animation, ready to render.

Blender's own PLY importer reads the surfaces but drops the per-face `crack` flag. This script
reads `run.json` and every `frames/surface_NNNN.ply` and makes one object per frame, shown only
on its own frame, with two materials ("perifrac surface", "perifrac crack") chosen per face by
the flag, which it also keeps as an integer face attribute `crack`; the frame's normals as
custom normals (smooth outside, flat cracks: the PLY's vertices are split where they should
not be smooth), its texture coordinates as the UV map `st`, its velocities as the point
attribute `velocity` (m/s) and its fragment ids as the face attribute `fragment`; a frame's
debris (`frames/debris_NNNN.ply`: pieces too small to be written as surfaces) becomes one more
object of icosahedra of the debris' radii, in the crack material. It adds the
run's balls (keyed per frame) and ground planes (or a backdrop floor below everything when the
run has none), turns the run's up axis (`run.json` "up") into Blender's +Z, and adds a camera
framed as `perifrac render` frames it, a sun and a fill light, the run's playback rate
(`run.json` "fps", 24 when absent) and Cycles render settings, so that

    blender -b out/wall/wall.blend -f 24

renders a frame with no further setup. Units are metres.

    blender --python tools/blender_import.py -- out/wall            # open Blender with it
    blender -b --python tools/blender_import.py -- out/wall --save out/wall/wall.blend
    blender -b --python tools/blender_import.py -- out/wall --frame 24 --report

With `--usd` it imports the run's USD cache instead (`DIR/NAME.usda`, written by `[output]
usd = true` or `perifrac export DIR --usd`; or `--usd FILE.usda`) through Blender's own USD
importer, which needs a Blender built with USD (pip's `bpy`, blender.org's builds; not Debian's
3.4): one mesh whose Mesh Sequence Cache reads each frame, with the `crack`, `fragment` and
`velocity` attributes, shaded by one material that follows `crack` (Blender assigns the cache's
per-subset materials at import only), and the same camera, lights and render settings.

    blender -b --python tools/blender_import.py -- out/wall --usd --save out/wall/wall.blend

Runs inside Blender 3.x, 4.x or 5.x (or Python with the `bpy` module); needs nothing beyond
Blender's Python.
"""

import json
import math
import os
import struct
import sys

import bpy
from mathutils import Matrix, Vector

SCALARS = {
    "char": "b", "int8": "b", "uchar": "B", "uint8": "B",
    "short": "h", "int16": "h", "ushort": "H", "uint16": "H",
    "int": "i", "int32": "i", "uint": "I", "uint32": "I",
    "float": "f", "float32": "f", "double": "d", "float64": "d",
}

# The camera of `perifrac render` (crates/cli/src/render.rs): horizontal field of view,
# azimuth from the first horizontal axis towards minus the second, elevation, and the share
# of the picture the framed bounds may fill.
FOV_DEG = 40.0
CAMERA_AZIMUTH_DEG = 50.0
CAMERA_ELEVATION_DEG = 25.0
FILL = 0.85
WIDTH, HEIGHT = 640, 480


def read_ply(path):
    """The elements of a PLY file as {name: list of rows (dicts)}."""
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
    out = {}
    if fmt == "ascii":
        tokens = iter(body.split())
        for name, count, props in elements:
            rows = out.setdefault(name, [])
            for _ in range(count):
                row = {}
                for p in props:
                    if p[1] == "list":
                        n = int(next(tokens))
                        row[p[0]] = [int(next(tokens)) for _ in range(n)]
                    else:
                        row[p[0]] = float(next(tokens))
                rows.append(row)
    else:
        order = "<" if fmt == "binary_little_endian" else ">"
        pos = 0
        for name, count, props in elements:
            rows = out.setdefault(name, [])
            scalar = all(p[1] != "list" for p in props)
            if scalar:
                # One struct for the whole row: fast for the vertex element.
                row_fmt = order + "".join(SCALARS[p[1]] for p in props)
                size = struct.calcsize(row_fmt)
                names = [p[0] for p in props]
                for values in struct.iter_unpack(row_fmt, body[pos:pos + size * count]):
                    rows.append(dict(zip(names, values)))
                pos += size * count
                continue
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
                rows.append(row)
    return out


def material(name, rgb):
    m = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    m.diffuse_color = (*rgb, 1.0)
    m.use_nodes = True
    bsdf = m.node_tree.nodes.get("Principled BSDF")
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
        bsdf.inputs["Roughness"].default_value = 0.5
    return m


def crack_material(surface_rgb, crack_rgb):
    """One material whose colour follows the face attribute `crack` (0 outside, 1 crack):
    what a changing-topology cache needs, since Blender assigns the cache's per-subset
    materials when it imports it and not again per frame."""
    m = bpy.data.materials.get("perifrac by crack") or bpy.data.materials.new("perifrac by crack")
    m.use_nodes = True
    nodes, links = m.node_tree.nodes, m.node_tree.links
    bsdf = nodes.get("Principled BSDF")
    attr = nodes.new("ShaderNodeAttribute")
    attr.attribute_name = "crack"
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.interpolation = "CONSTANT"
    ramp.color_ramp.elements[0].position = 0.0
    ramp.color_ramp.elements[0].color = (*surface_rgb, 1.0)
    ramp.color_ramp.elements[1].position = 0.5
    ramp.color_ramp.elements[1].color = (*crack_rgb, 1.0)
    links.new(attr.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.5
    return m


def fcurves(action):
    """The F-curves of an action: `action.fcurves` up to Blender 4.x, the channel bags of its
    layered strips from 4.4 on (Blender 5 has only these)."""
    if hasattr(action, "fcurves"):
        return list(action.fcurves)
    curves = []
    for layer in getattr(action, "layers", []):
        for strip in layer.strips:
            for bag in getattr(strip, "channelbags", []):
                curves.extend(bag.fcurves)
    return curves


def show_only_on(obj, frame, last):
    """Key the object visible on `frame` and hidden on the frames around it."""
    for f, hidden in ((frame - 1, True), (frame, False), (frame + 1, True)):
        if 0 <= f <= last:
            obj.hide_viewport = hidden
            obj.hide_render = hidden
            obj.keyframe_insert("hide_viewport", frame=f)
            obj.keyframe_insert("hide_render", frame=f)
    for curve in fcurves(obj.animation_data.action):
        for k in curve.keyframe_points:
            k.interpolation = "CONSTANT"


def frame_mesh(name, ply, surface_mat, crack_mat):
    """A mesh from a frame PLY, with its crack flags, normals, UVs, velocities, fragments."""
    rows = ply["vertex"]
    faces = [f.get("vertex_indices") or f.get("vertex_index") for f in ply.get("face", [])]
    crack = [int(f.get("crack", 0)) for f in ply.get("face", [])]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([(r["x"], r["y"], r["z"]) for r in rows], [], faces)
    mesh.materials.append(surface_mat)
    mesh.materials.append(crack_mat)
    mesh.polygons.foreach_set("material_index", crack)
    attr = mesh.attributes.new("crack", "INT", "FACE")
    attr.data.foreach_set("value", crack)
    if faces and "fragment" in ply["face"][0]:
        frag = mesh.attributes.new("fragment", "INT", "FACE")
        frag.data.foreach_set("value", [int(f["fragment"]) for f in ply["face"]])
    if rows and "vx" in rows[0]:
        vel = mesh.attributes.new("velocity", "FLOAT_VECTOR", "POINT")
        vel.data.foreach_set("vector", [c for r in rows for c in (r["vx"], r["vy"], r["vz"])])
    if rows and "s" in rows[0]:
        uv = mesh.uv_layers.new(name="st")
        loops = [0] * len(mesh.loops)
        mesh.loops.foreach_get("vertex_index", loops)
        uv.data.foreach_set("uv", [c for v in loops for c in (rows[v]["s"], rows[v]["t"])])
    mesh.polygons.foreach_set("use_smooth", [True] * len(mesh.polygons))
    if rows and "nx" in rows[0]:
        if hasattr(mesh, "use_auto_smooth"):
            mesh.use_auto_smooth = True  # custom normals need it before Blender 4.1
        mesh.normals_split_custom_set_from_vertices(
            [(r["nx"], r["ny"], r["nz"]) for r in rows]
        )
    mesh.update()
    return mesh, len(rows), len(faces), sum(crack)


# The unit icosahedron: each debris point becomes one, scaled to the point's radius.
_T = (1.0 + 5.0 ** 0.5) / 2.0
_N = (1.0 + _T * _T) ** 0.5
ICO_VERTICES = [(a / _N, b / _N, c / _N) for a, b, c in (
    (-1, _T, 0), (1, _T, 0), (-1, -_T, 0), (1, -_T, 0),
    (0, -1, _T), (0, 1, _T), (0, -1, -_T), (0, 1, -_T),
    (_T, 0, -1), (_T, 0, 1), (-_T, 0, -1), (-_T, 0, 1))]
ICO_FACES = [
    (0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
    (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
    (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]


def debris_mesh(name, ply, crack_mat):
    """A frame's debris points (`frames/debris_NNNN.ply`) as icosahedra of their radii, with
    the `fragment` and `velocity` of their point on every vertex."""
    rows = ply.get("vertex", [])
    vertices, faces, fragment, velocity = [], [], [], []
    for r in rows:
        base = len(vertices)
        vertices.extend((r["x"] + r["radius"] * a, r["y"] + r["radius"] * b,
                         r["z"] + r["radius"] * c) for a, b, c in ICO_VERTICES)
        faces.extend(tuple(base + k for k in f) for f in ICO_FACES)
        fragment.extend([int(r.get("fragment", 0))] * len(ICO_VERTICES))
        velocity.extend((r.get("vx", 0.0), r.get("vy", 0.0), r.get("vz", 0.0)) * len(ICO_VERTICES))
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(vertices, [], faces)
    mesh.materials.append(crack_mat)
    frag = mesh.attributes.new("fragment", "INT", "POINT")
    frag.data.foreach_set("value", fragment)
    vel = mesh.attributes.new("velocity", "FLOAT_VECTOR", "POINT")
    vel.data.foreach_set("vector", velocity)
    mesh.update()
    return mesh, len(rows)


def bounds_union(boxes):
    lo = [min(b["min"][k] for b in boxes) for k in range(3)]
    hi = [max(b["max"][k] for b in boxes) for k in range(3)]
    return lo, hi


def camera_view(run):
    """Camera location, target, and the lowest point any frame reaches along up, as
    `perifrac render` computes them (data coordinates)."""
    up = Vector(run.get("up", (0.0, 0.0, 1.0))).normalized()
    boxes = [run["rest_bounds"]] if run.get("rest_bounds") else []
    boxes += [f.get("main_bounds") or f.get("bounds") for f in run["frames"]]
    boxes = [b for b in boxes if b]
    lo, hi = bounds_union(boxes)
    axis = min(range(3), key=lambda i: abs(up[i]))
    e1 = Vector((0.0, 0.0, 0.0))
    e1[axis] = 1.0
    e1 = (e1 - up * e1.dot(up)).normalized()
    e2 = up.cross(e1)

    def direction(azimuth, elevation):
        a, e = math.radians(azimuth), math.radians(elevation)
        horizontal = e1 * math.cos(a) - e2 * math.sin(a)
        return (horizontal * math.cos(e) + up * math.sin(e)).normalized()

    to_camera = direction(CAMERA_AZIMUTH_DEG, CAMERA_ELEVATION_DEG)
    forward = -to_camera
    right = forward.cross(up).normalized()
    cam_up = right.cross(forward)
    target = (Vector(lo) + Vector(hi)) * 0.5
    extent = max(max(hi[k] - lo[k] for k in range(3)), 1e-6)
    tan_x = math.tan(math.radians(FOV_DEG) / 2.0) * FILL
    tan_y = tan_x * HEIGHT / WIDTH
    distance = extent * 0.5 / min(tan_x, tan_y)
    lowest = math.inf
    for c in range(8):
        p = Vector([hi[k] if c >> k & 1 else lo[k] for k in range(3)])
        rel = p - target
        x, y, z = rel.dot(right), rel.dot(cam_up), rel.dot(forward)
        distance = max(distance, abs(x) / tan_x - z, abs(y) / tan_y - z)
        lowest = min(lowest, p.dot(up))
    for f in run["frames"]:
        b = f.get("bounds")
        if b:
            for c in range(8):
                p = Vector([b["max"][k] if c >> k & 1 else b["min"][k] for k in range(3)])
                lowest = min(lowest, p.dot(up))
    location = target + to_camera * distance
    rotation = Matrix((right, cam_up, -forward)).transposed()
    return location, rotation, target, extent, lowest, up, direction


def link(obj, col, root):
    for c in list(obj.users_collection):
        c.objects.unlink(obj)
    col.objects.link(obj)
    obj.parent = root


def import_run(run_dir, only=None, usd=None):
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
    fps = float(run.get("fps", 24.0))
    scene.render.fps = max(1, round(fps))
    scene.render.fps_base = scene.render.fps / fps
    col = bpy.data.collections.new("perifrac " + run.get("scene", run_dir))
    scene.collection.children.link(col)
    # Everything hangs under one empty that turns the run's up axis into +Z.
    root = bpy.data.objects.new("perifrac", None)
    col.objects.link(root)
    up = Vector(run.get("up", (0.0, 0.0, 1.0))).normalized()
    root.rotation_mode = "QUATERNION"
    root.rotation_quaternion = up.rotation_difference(Vector((0.0, 0.0, 1.0)))
    surface_mat = material("perifrac surface", (0.62, 0.60, 0.55))
    crack_mat = material("perifrac crack", (0.90, 0.38, 0.06))
    report = []
    if usd is not None:
        # The run's USD cache through Blender's own importer (a Mesh Sequence Cache that reads
        # every frame); the stage is z-up already, so it stays outside the rotated root.
        bpy.ops.wm.usd_import(filepath=os.path.abspath(usd))
        surface = bpy.data.objects.get("surface")
        if surface is None:
            raise ValueError(f"{usd}: no mesh named surface (a --pieces cache is not handled)")
        by_crack = crack_material((0.62, 0.60, 0.55), (0.90, 0.38, 0.06))
        for slot in surface.material_slots:
            slot.material = by_crack
        debris = bpy.data.objects.get("debris")
        if debris is not None and hasattr(debris.data, "materials"):
            debris.data.materials.clear()
            debris.data.materials.append(crack_mat)
        frames = []
    for fr in frames:
        ply = read_ply(os.path.join(run_dir, fr["surface"]))
        mesh, nv, nf, nc = frame_mesh(f"frame_{fr['index']:04d}", ply, surface_mat, crack_mat)
        obj = bpy.data.objects.new(mesh.name, mesh)
        link(obj, col, root)
        if only is None:
            show_only_on(obj, fr["index"], scene.frame_end)
        report.append((fr["index"], nv, nf, nc))
        if fr.get("debris"):
            dply = read_ply(os.path.join(run_dir, fr["debris"]["path"]))
            dmesh, _ = debris_mesh(f"debris_{fr['index']:04d}", dply, crack_mat)
            dobj = bpy.data.objects.new(dmesh.name, dmesh)
            link(dobj, col, root)
            if only is None:
                show_only_on(dobj, fr["index"], scene.frame_end)
    ball_mat = material("perifrac ball", (0.55, 0.57, 0.60))
    balls = [] if usd is not None else run["frames"][0].get("balls", [])
    for b, ball in enumerate(balls):
        bpy.ops.mesh.primitive_uv_sphere_add(radius=ball["radius"], location=ball["center"])
        obj = bpy.context.active_object
        obj.name = f"ball_{b}"
        obj.data.materials.append(ball_mat)
        link(obj, col, root)
        for fr in run["frames"]:
            obj.location = fr["balls"][b]["center"]
            obj.keyframe_insert("location", frame=fr["index"])
    location, rotation, target, extent, lowest, _, direction = camera_view(run)
    grounds = run.get("grounds", [])
    floors = [(g["point"], g["normal"]) for g in grounds]
    if usd is not None:
        floors = []  # the cache carries its ground planes
    if not grounds:
        # No ground in the run: a backdrop floor below everything any frame holds.
        point = target + up * (lowest - 0.05 * extent - target.dot(up))
        floors = [(tuple(point), tuple(up))]
    for g, (point, normal) in enumerate(floors):
        bpy.ops.mesh.primitive_plane_add(size=40.0 * extent, location=point)
        obj = bpy.context.active_object
        obj.name = f"ground_{g}" if grounds else "backdrop"
        obj.rotation_mode = "QUATERNION"
        obj.rotation_quaternion = Vector((0.0, 0.0, 1.0)).rotation_difference(Vector(normal))
        obj.data.materials.append(material("perifrac floor", (0.45, 0.45, 0.43)))
        link(obj, col, root)
    camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    camera.data.sensor_fit = "HORIZONTAL"
    camera.data.angle = math.radians(FOV_DEG)
    camera.data.clip_end = max(100.0, 100.0 * extent)
    camera.data.clip_start = min(0.1, 0.001 * extent)
    camera.matrix_basis = Matrix.Translation(location) @ rotation.to_4x4()
    link(camera, col, root)
    scene.camera = camera
    for name, azimuth, elevation, energy in (("key", 30.0, 55.0, 2.5), ("fill", -40.0, 20.0, 0.6)):
        light = bpy.data.objects.new(name, bpy.data.lights.new(name, "SUN"))
        light.data.energy = energy
        towards = direction(CAMERA_AZIMUTH_DEG - azimuth, elevation)
        # A sun shines along its -Z: point that from the light's side towards the target.
        light.rotation_mode = "QUATERNION"
        light.rotation_quaternion = Vector((0.0, 0.0, 1.0)).rotation_difference(towards)
        light.location = target + towards * 2.0 * extent
        link(light, col, root)
    if scene.world is None:
        scene.world = bpy.data.worlds.new("perifrac")
    scene.world.color = (0.78, 0.86, 0.95)
    scene.world.use_nodes = True
    background = scene.world.node_tree.nodes.get("Background")
    if background is not None:
        background.inputs["Color"].default_value = (0.78, 0.86, 0.95, 1.0)
        background.inputs["Strength"].default_value = 0.35
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = 16
    if hasattr(scene.cycles, "use_denoising"):
        scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.filepath = "//render/frame_"
    return report


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not argv:
        raise SystemExit("usage: blender --python tools/blender_import.py -- RUN_DIR "
                         "[--frame N] [--usd [CACHE.usda]] [--save FILE.blend] [--report]")
    run_dir, only, save, report, usd = argv[0], None, None, False, None
    rest = argv[1:]
    while rest:
        opt = rest.pop(0)
        if opt == "--frame":
            only = int(rest.pop(0))
        elif opt == "--save":
            save = rest.pop(0)
        elif opt == "--report":
            report = True
        elif opt == "--usd":
            usd = rest.pop(0) if rest and rest[0].endswith(".usda") else None
            if usd is None:
                with open(os.path.join(run_dir, "run.json")) as f:
                    stem = os.path.splitext(json.load(f)["scene"])[0]
                usd = os.path.join(run_dir, stem + ".usda")
        else:
            raise SystemExit(f"unknown option {opt}")
    if bpy.app.background:
        bpy.ops.wm.read_factory_settings(use_empty=True)
    rows = import_run(run_dir, only, usd)
    if report:
        print(f"perifrac blender {bpy.app.version_string}")
        for index, nv, nf, nc in rows:
            print(f"perifrac frame {index}: {nv} vertices, {nf} faces, {nc} crack faces")
    if save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(save))


if __name__ == "__main__":
    main()
