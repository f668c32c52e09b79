"""Checks every piece of every frame of a perifrac run directory, independently of perifrac:

    python3 tests/python/check_pieces.py RUN_DIR [--quiet]

Each frame's surface PLY is read with plyfile; split shading vertices are welded back through
their `vertex_id`; faces are grouped by their `fragment` id; each piece must be closed (every
edge used by exactly two of its faces, once in each direction: consistently oriented and
2-manifold along edges) and enclose a positive volume (divergence theorem, in float64).
Prints one line per frame with the counts and every bad piece, then a summary line
`pieces: N checked, B open, M non-manifold, I inside out` and exits 1 when any is bad.
"""

import json
import os
import sys
from collections import Counter

import numpy as np
import plyfile


def check_frame(path):
    d = plyfile.PlyData.read(path)
    v, f = d["vertex"].data, d["face"].data
    ids = np.asarray(v["vertex_id"], dtype=np.int64)
    pos = np.stack([v["x"], v["y"], v["z"]], axis=1).astype(np.float64)
    faces = ids[np.stack(f["vertex_indices"]).astype(np.int64)]
    welded = np.zeros((ids.max() + 1 if len(ids) else 0, 3))
    welded[ids] = pos
    frag = np.asarray(f["fragment"], dtype=np.int64)
    bad = []
    counts = Counter()
    for piece in np.unique(frag):
        tri = faces[frag == piece]
        counts["pieces"] += 1
        directed = Counter()
        for a, b, c in tri:
            for e in ((a, b), (b, c), (c, a)):
                directed[e] += 1
        problem = None
        if any(n > 1 for n in directed.values()):
            problem = "non-manifold"
        elif any(directed.get((b, a), 0) != 1 for (a, b) in directed):
            problem = "open"
        p = welded[tri]
        volume = np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6.0
        if problem is None and not volume > 0.0:
            problem = "inside out"
        if problem:
            counts[problem] += 1
            bad.append((int(piece), problem, len(tri), volume))
    return counts, bad


def main():
    run = sys.argv[1]
    quiet = "--quiet" in sys.argv[2:]
    manifest = json.load(open(os.path.join(run, "run.json")))
    total = Counter()
    for frame in manifest["frames"]:
        counts, bad = check_frame(os.path.join(run, frame["surface"]))
        total.update(counts)
        if not quiet or bad:
            print(f"frame {frame['index']}: {counts['pieces']} pieces, {len(bad)} bad")
        for piece, problem, n, volume in bad:
            print(f"  fragment {piece}: {problem} ({n} faces, volume {volume:.3e})")
    print(f"pieces: {total['pieces']} checked, {total['open']} open, "
          f"{total['non-manifold']} non-manifold, {total['inside out']} inside out")
    sys.exit(1 if total["open"] + total["non-manifold"] + total["inside out"] else 0)


if __name__ == "__main__":
    main()
