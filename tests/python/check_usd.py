"""Checks a perifrac USD cache against its run directory with Pixar's USD library (usd-core).

    python3 tests/python/check_usd.py RUN_DIR CACHE.usda [--pieces]

Opens the cache, runs every validator USD registers (UsdValidation) and fails on any error;
then, frame by frame, compares the cache with the PLY frames it was made from (read with
plyfile): the mesh's points, normals, face counts and indices, crack flags (primvar and the
two GeomSubsets), fragment ids and texture coordinates (zeros for a shell run's frames, which
have none) exactly, and velocities as the frames' times the playback factor (to f32 rounding). With --pieces, each fragment prim's points plus
its translation must give the frame's points of that fragment (to f32 rounding) and only the
fragments of the frame may be visible. Prints one line per frame and exits non-zero on the
first mismatch.
"""

import json
import os
import sys

import numpy as np
import plyfile
from pxr import Gf, Usd, UsdGeom, UsdValidation


def fail(message):
    print("MISMATCH: " + message)
    sys.exit(1)


def validate(stage):
    registry = UsdValidation.ValidationRegistry()
    validators = registry.GetOrLoadAllValidators()
    errors = UsdValidation.ValidationContext(validators).Validate(stage)
    bad = [e for e in errors if e.GetType() == UsdValidation.ValidationErrorType.Error]
    for e in errors:
        print("validator:", e.GetType(), e.GetName(), e.GetMessage())
    if bad:
        fail(f"{len(bad)} validation errors")
    print(f"validators: {len(validators)} run, {len(errors)} findings, 0 errors")


def read_frame(path):
    d = plyfile.PlyData.read(path)
    v = d["vertex"].data
    f = d["face"].data
    return {
        "points": np.stack([v["x"], v["y"], v["z"]], axis=1).astype(np.float32),
        "normals": np.stack([v["nx"], v["ny"], v["nz"]], axis=1).astype(np.float32),
        "velocities": np.stack([v["vx"], v["vy"], v["vz"]], axis=1).astype(np.float32),
        # A shell frame has no texture coordinates: the cache writes zeros.
        "st": (np.stack([v["s"], v["t"]], axis=1).astype(np.float32)
               if "s" in v.dtype.names else np.zeros((len(v), 2), np.float32)),
        "faces": np.stack(f["vertex_indices"]).astype(np.int64),
        "crack": np.asarray(f["crack"], dtype=np.int64),
        "fragment": np.asarray(f["fragment"], dtype=np.int64),
    }


def same(name, got, want):
    got = np.asarray(got)
    if got.shape != want.shape or not np.array_equal(got, want):
        fail(f"{name}: cache {got.shape} differs from the frame {want.shape}")


def main():
    run, cache = sys.argv[1], sys.argv[2]
    pieces = "--pieces" in sys.argv[3:]
    manifest = json.load(open(os.path.join(run, "run.json")))
    stage = Usd.Stage.Open(cache)
    validate(stage)
    if UsdGeom.GetStageUpAxis(stage) != "Z" or UsdGeom.GetStageMetersPerUnit(stage) != 1.0:
        fail("stage is not z-up in metres")
    fps = stage.GetTimeCodesPerSecond()
    frames = manifest["frames"]
    if stage.GetEndTimeCode() != len(frames) - 1:
        fail(f"end time code {stage.GetEndTimeCode()} for {len(frames)} frames")
    per_frame = frames[-1]["time"] / (len(frames) - 1)
    speed = np.float32(per_frame * fps)
    root = stage.GetDefaultPrim()
    for k, frame in enumerate(frames):
        want = read_frame(os.path.join(run, frame["surface"]))
        t = Usd.TimeCode(k)
        if pieces:
            check_pieces(stage, root, want, t, k, frame)
            continue
        mesh = UsdGeom.Mesh(root.GetChild("surface"))
        same(f"frame {k} points", mesh.GetPointsAttr().Get(t), want["points"])
        same(f"frame {k} normals", mesh.GetNormalsAttr().Get(t), want["normals"])
        same(f"frame {k} counts", mesh.GetFaceVertexCountsAttr().Get(t),
             np.full(len(want["faces"]), 3))
        same(f"frame {k} indices", mesh.GetFaceVertexIndicesAttr().Get(t),
             want["faces"].reshape(-1))
        api = UsdGeom.PrimvarsAPI(mesh)
        same(f"frame {k} crack", api.GetPrimvar("crack").Get(t), want["crack"])
        same(f"frame {k} fragment", api.GetPrimvar("fragment").Get(t), want["fragment"])
        same(f"frame {k} st", api.GetPrimvar("st").Get(t), want["st"])
        vel = np.asarray(mesh.GetVelocitiesAttr().Get(t))
        same(f"frame {k} velocities", vel, want["velocities"] * speed)
        subsets = {s.GetPrim().GetName(): s for s in UsdGeom.Subset.GetAllGeomSubsets(mesh)}
        crack = np.flatnonzero(want["crack"])
        outside = np.flatnonzero(want["crack"] == 0)
        same(f"frame {k} crack subset", subsets["crack"].GetIndicesAttr().Get(t), crack)
        same(f"frame {k} outside subset", subsets["outside"].GetIndicesAttr().Get(t), outside)
        extent = mesh.GetExtentAttr().Get(t)
        same(f"frame {k} extent", extent,
             np.stack([want["points"].min(axis=0), want["points"].max(axis=0)]))
        for b, ball in enumerate(frame["balls"]):
            xf = UsdGeom.Xformable(root.GetChild(f"ball_{b}"))
            at = xf.ComputeLocalToWorldTransform(t).ExtractTranslation()
            if max(abs(at[i] - ball["center"][i]) for i in range(3)) > 1e-12:
                fail(f"frame {k} ball {b} at {at}, run.json {ball['center']}")
        print(f"frame {k}: {len(want['points'])} points, {len(want['faces'])} faces, "
              f"{len(crack)} crack faces: equal")


def check_pieces(stage, root, want, t, k, frame):
    scope = root.GetChild("fragments")
    alive = set(int(f) for f in np.unique(want["fragment"]))
    shown = set()
    for prim in scope.GetChildren():
        fid = int(prim.GetName()[2:])
        visible = UsdGeom.Imageable(prim).ComputeVisibility(t) != UsdGeom.Tokens.invisible
        if visible:
            shown.add(fid)
    if shown != alive:
        fail(f"frame {k}: visible fragments {sorted(shown)[:10]} vs {sorted(alive)[:10]}")
    total = 0
    for fid in alive:
        prim = scope.GetChild(f"f_{fid}")
        mesh = UsdGeom.Mesh(prim)
        local = np.asarray(mesh.GetPointsAttr().Get(t), dtype=np.float64)
        xf = UsdGeom.Xformable(prim).ComputeLocalToWorldTransform(t)
        move = np.array(xf.ExtractTranslation())
        faces = np.asarray(mesh.GetFaceVertexIndicesAttr().Get(t)).reshape(-1, 3)
        mine = want["faces"][want["fragment"] == fid]
        if len(faces) != len(mine):
            fail(f"frame {k} fragment {fid}: {len(faces)} faces, frame {len(mine)}")
        got = local[faces] + move
        ref = want["points"][mine].astype(np.float64)
        scale = max(1.0, float(np.abs(ref).max()))
        if np.abs(got - ref).max() > 4 * np.finfo(np.float32).eps * scale:
            fail(f"frame {k} fragment {fid}: corners off by {np.abs(got - ref).max()}")
        total += len(faces)
    print(f"frame {k}: {len(alive)} fragments, {total} faces: equal")


if __name__ == "__main__":
    main()
