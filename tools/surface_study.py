"""Issue 18's surface study: Chen's model linearised about the rest state, solved statically
on the accuracy benchmark's bars, with and without ghost particles mirrored across the bar's
side faces. Independent of perifrac's physics crate (it only calls `perifrac mesh`).

    python3 tools/surface_study.py cantilever --mesh unstructured --cells 4 [--ghosts]
        [--clamp mirror|mirror2]
    python3 tools/surface_study.py moduli --mesh unstructured --nu 0.3 [--ghosts]
    python3 tools/surface_study.py interior --mesh kuhn

`cantilever`: the 1 x 0.1 x 0.1 m bar of `perifrac bench accuracy --case cantilever` (10 n
cells along, n across, a clamp layer of ceil(1.5 x 1.3) = 2 cells behind x = 0 held, gravity
on rho = 1000 kg/m^3, E = 1e8 Pa, nu = 0.3, k = 1.5); prints the tip's deflection (a line
fitted over the last two cells, at x = 1) against the P2 answer 0.014728 m, its sideways
deflection over its vertical one, and the deflection curve split in two (`curve`): "bending",
the bar's bending compliance against the continuum's, and "root", shear and the clamp's offset
and rotation carried to the tip, both over Euler-Bernoulli's tip. `--clamp mirror` replaces
the held layer by the bar's own image across x = 0 moving as minus its source (the odd
reflection: zero displacement on the face, right for every field that is zero there and
linear in x, so to first order only): a ghost layer like the side faces', carrying no energy
of its own. `--clamp mirror2` adds to each image the even part the odd reflection flips,
`u_xx x^2` with `x` the source's depth and `u_xx` from a quadratic fit over the real family
of its real source: right to second order in x.

`moduli`: the 0.4 x 0.1 x 0.1 m bar of `--case moduli` (32 x 8 x 8 cells, end layers as deep
as the clamp held, one pulled by 0.1%); prints E (the pulled layer's reaction over the
section, over the axial strain fitted over the middle third) and nu (the lateral strains
fitted there).

`interior`: a 0.4 x 0.1 x 0.1 m bar of 32 x 8 x 8 cells (the moduli bar without its end
layers), its particles more than a horizon from every face (whole families, no surface): their
energy under an affine uniaxial stress along x over the continuum's, and their energy under
pure bending beyond the continuum's, over `E kappa^2 delta^2`, against its closed form (the
nonlocal model's own bending stiffness, `bending_excess`).

The model is docs/model.md section 2 with perifrac's default correction: each particle's dilatation
read through fitted weights `omega (n n : L_i)` with `sum_j omega (n n : L_i) r n n V_j = I`,
and its deviatoric constant `b_i = 15 mu / (2 sum_j omega r^2 V_j)`; the energy
`sum_i V_i (kappa theta_i^2 / 2 + b_i sum_j omega ed_ij^2 V_j)` with `ed = e - theta r / 3`
and `e = n . (u_j - u_i)`. The fit's bound (`FIT_BOUND`, a blend towards the scalar
calibration where a weight passes 10 times it) is left out. Families are horizon balls (on a
convex box, where the face walk of docs/model.md finds nearly the same). Linear: the benchmarks'
loads strain the bars by under 0.3%.

`--ghosts`: every particle within a horizon of a side face (y or z) is mirrored across it
(and across both faces at an edge); a ghost joins the families it falls in, carries no energy
of its own, and moves with its source `p` as `u_p + F_p (X_g - X_p)`, `F_p` the least-squares
gradient over `p`'s real family (exact for every affine field, rotations included). The fit
and `b_i` then run over the completed families. `--implicit`: `F_p` over `p`'s whole family,
ghosts included, so the ghosts' displacements solve a linear system together (a constrained
solve here).

`--order 2`: the ghosts extrapolated by a quadratic least-squares fit over the source's real
family in place of the affine one.

Needs numpy, scipy and meshio; pypardiso, if installed, solves in a fraction of the time and
memory (the 60 x 6 x 6 bar with ghosts does not fit in 24 GB without it). Cost here, with
pypardiso: seconds for the 20 x 2 x 2 cantilever, about a minute at 40 x 4 x 4; the moduli bar
with ghosts 5 minutes and 18 GB (one run at a time).
"""

import argparse
import math
import os
import subprocess
import sys
import tempfile

try:
    import meshio
    import numpy as np
    import scipy.sparse as sp
    from scipy.spatial import cKDTree
except ImportError as missing:
    sys.exit(f"surface_study: needs numpy, scipy and meshio ({missing}): "
             "python3 -m pip install numpy scipy meshio")

try:
    import pypardiso

    def solve(a, b):
        """Solves the sparse system `a x = b` (Intel's PARDISO)."""
        return pypardiso.spsolve(a.tocsr(), b)

except ImportError:
    import scipy.sparse.linalg as spl

    def solve(a, b):
        """Solves the sparse system `a x = b` (SuperLU)."""
        return spl.spsolve(a.tocsc(), b)


E0 = 1e8
RHO, GRAVITY = 1000.0, 9.81
K_HORIZON = 1.5
KUHN_EDGE_PER_CELL = 1.3  # crates/bench/src/bar.rs: the clamp layer's cells per horizon factor
P2_TIP = 0.014728  # m, BENCHMARKS.md: the project's P2 tets converged


def mesh_box(perifrac, length, cells, unstructured, out):
    """Meshes the box `length x 0.1 x 0.1` m of `cells` with `perifrac mesh` into `out`;
    returns the vertices, the tets' barycentres and volumes, and the mean edge length (m)."""
    args = [perifrac, "mesh", f"box:{length}x0.1x0.1", "--cells", ",".join(map(str, cells)),
            "-o", out]
    if unstructured:
        args.append("--unstructured")
    try:
        subprocess.run(args, check=True, capture_output=True, text=True)
    except FileNotFoundError:
        sys.exit(f"surface_study: no perifrac at {perifrac}: build it with `cargo build --release "
                 "-p perifrac` or give its path with --perifrac")
    except subprocess.CalledProcessError as e:
        sys.exit(f"surface_study: `{' '.join(args)}` failed:\n{e.stderr}")
    m = meshio.read(out)
    x, t = m.points, m.cells_dict["tetra"]
    p = x[t]
    a, b, c = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]
    vol = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c))) / 6
    edges = np.unique(np.sort(t[:, [[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]]].reshape(-1, 2),
                              axis=1), axis=0)
    lam = np.linalg.norm(x[edges[:, 0]] - x[edges[:, 1]], axis=1).mean()
    return x, p.mean(axis=1), vol, lam


def basis(d, order):
    """The least-squares fit's terms of an offset `d`: linear, or linear and quadratic."""
    if order == 1:
        return d
    x, y, z = d.T
    return np.stack([x, y, z, x * x / 2, y * y / 2, z * z / 2, x * y, x * z, y * z], 1)


class Model:
    """Bonds of the real particles (ghosts appended after them) and their constants."""

    def __init__(self, bary, vol, lam, nu, lo, hi, ghosts, clamp=0):
        """Particles at `bary` of volumes `vol`, horizon `K_HORIZON * lam`; with `ghosts`,
        mirror images across the box `[lo, hi]`'s faces normal to y and z; with `clamp` 1 or
        2, every point (real or ghost) within a horizon of the face `x = lo` mirrored across
        it, moving as minus its source (the odd reflection: zero displacement on the face) and,
        at 2, plus `u_xx x^2` (see `static`)."""
        n = len(bary)
        delta = K_HORIZON * lam
        pts, vols, src = [bary], [vol], [np.arange(n)]
        if ghosts:
            for ay in (None, 0, 1):
                for az in (None, 0, 1):
                    if ay is None and az is None:
                        continue
                    g = bary.copy()
                    near = np.ones(n, bool)
                    for axis, side in ((1, ay), (2, az)):
                        if side is None:
                            continue
                        plane = (lo, hi)[side][axis]
                        g[:, axis] = 2 * plane - g[:, axis]
                        near &= np.abs(bary[:, axis] - plane) < delta
                    pts.append(g[near])
                    vols.append(vol[near])
                    src.append(np.flatnonzero(near))
        self.nside = sum(len(v) for v in vols)
        self.csrc, self.clamp = None, clamp
        if clamp:
            both = np.vstack(pts)
            near = both[:, 0] - lo[0] < delta
            g = both[near].copy()
            g[:, 0] = 2 * lo[0] - g[:, 0]
            pts.append(g)
            vols.append(np.concatenate(vols)[near])
            self.csrc = np.flatnonzero(near)
            self.depth = both[near, 0] - lo[0]
        self.n, self.bary, self.vol = n, bary, vol
        self.pos, self.src = np.vstack(pts), np.concatenate(src)
        self.rows = {}
        allvol = np.concatenate(vols)
        found = cKDTree(self.pos).query_ball_point(bary, delta, return_sorted=True)
        i = np.repeat(np.arange(n), [len(f) for f in found])
        j = np.concatenate([np.asarray(f, int) for f in found])
        keep = i != j
        self.i, self.j = i[keep], j[keep]
        xi = self.pos[self.j] - bary[self.i]
        self.xi, self.r = xi, np.linalg.norm(xi, axis=1)
        self.nv = xi / self.r[:, None]
        self.wv = delta / self.r * allvol[self.j]  # omega V_j
        mu, self.kappa = E0 / (2 * (1 + nu)), E0 / (3 * (1 - 2 * nu))
        self.b = 15 * mu / (2 * np.bincount(self.i, self.wv * self.r ** 2, n))
        nx, ny, nz = self.nv.T
        p = np.stack([nx * nx, ny * ny, nz * nz, 2 * nx * ny, 2 * nx * nz, 2 * ny * nz], 1)
        q = p * [1, 1, 1, 0.5, 0.5, 0.5]
        a = np.zeros((n, 6, 6))
        np.add.at(a, self.i, (self.wv * self.r)[:, None, None] * q[:, :, None] * p[:, None, :])
        l = np.linalg.solve(a, np.tile([1.0, 1, 1, 0, 0, 0], (n, 1))[..., None])[..., 0]
        self.dv = self.wv * np.einsum("ij,ij->i", p, l[self.i])  # fitted weight times V_j
        # The correction's factors on docs/model.md's constants, as `perifrac run` prints them: per
        # particle, the dilatation weight of largest magnitude and b_i.
        dil = np.zeros(n)
        np.maximum.at(dil, self.i, np.abs(self.dv / self.wv))
        self.factors = (dil / (9 / (4 * math.pi * delta ** 4)),
                        self.b / (15 * mu / (2 * math.pi * delta ** 5)))

    def fit(self, whole, order):
        """The least-squares fit over each real particle's real family (or, when `whole`, its
        whole family): the bonds used (`ir`, `jr`, `wr`: ends and `omega V_j`), their basis
        terms `phi` and each particle's inverse moment `inv` (n x terms x terms)."""
        use = np.ones(len(self.i), bool) if whole else self.j < self.n
        ir, jr, wr = self.i[use], self.j[use], self.wv[use]
        phi = basis(self.xi[use], order)
        size = phi.shape[1]
        shape = np.zeros((self.n, size, size))
        np.add.at(shape, ir, wr[:, None, None] * phi[:, :, None] * phi[:, None, :])
        return ir, jr, wr, phi, np.linalg.inv(shape)

    def ghost_rows(self, whole, order=1):
        """(3 m x 3 N): each ghost's displacement `u_p + F_p (X_g - X_p)` from every particle's,
        `F_p` the least-squares gradient over `p`'s real family or, when `whole`, over its whole
        family (ghosts included). Built once for each `(whole, order)`."""
        key = (whole, order)
        if key not in self.rows:
            self.rows[key] = self.build_ghost_rows(whole, order)
        return self.rows[key]

    def build_ghost_rows(self, whole, order):
        """`ghost_rows`, computed."""
        n, na = self.n, self.nside
        if na == n:
            return sp.csr_matrix((0, 3 * len(self.pos)))
        ir, jr, wr, phi, inv = self.fit(whole, order)
        start = np.searchsorted(ir, np.arange(n))
        end = np.searchsorted(ir, np.arange(n), "right")
        g = np.arange(na - n)
        p = self.src[n:]
        k = np.einsum("gab,gb->ga", inv[p], basis(self.pos[n:na] - self.bary[p], order))
        gi = np.repeat(g, end[p] - start[p])
        bi = np.concatenate([np.arange(s, e) for s, e in zip(start[p], end[p])] + [[]]).astype(int)
        c = wr[bi] * np.einsum("ia,ia->i", phi[bi], k[gi])
        return per_axis(gi, jr[bi], c, g, p, 1 - np.bincount(gi, c, len(g)),
                        (3 * len(g), 3 * len(self.pos)))

    def curvature(self):
        """(3 N x 3 N): each real particle's `u_xx` from the quadratic least-squares fit over
        its real family."""
        n = self.n
        ir, jr, wr, phi, inv = self.fit(False, 2)
        # row 3 of the inverse reads the coefficient of x^2 / 2, which is u_xx
        c = wr * np.einsum("ia,ia->i", phi, inv[ir, 3, :])
        own = np.arange(n)
        return per_axis(ir, jr, c, own, own, -np.bincount(ir, c, n), (3 * n, 3 * n))

    def energy_density(self, u):
        """Each real particle's energy density (J/m^3) under the displacements `u` (N x 3)."""
        e = np.einsum("ij,ij->i", self.nv, u[self.j] - u[self.i])
        theta = np.bincount(self.i, self.dv * e, self.n)
        ed = e - theta[self.i] * self.r / 3
        return self.kappa * theta ** 2 / 2 + self.b * np.bincount(self.i, self.wv * ed ** 2, self.n)

    def hessian(self):
        """The energy's Hessian over every particle's displacement, ghosts as free points."""
        n, na, nb = self.n, len(self.pos), len(self.i)
        b = np.arange(nb)
        cols = np.stack([3 * self.j + a for a in range(3)] + [3 * self.i + a for a in range(3)], 1)
        ext = sp.csr_matrix((np.concatenate([self.nv, -self.nv], 1).ravel(),
                             (np.repeat(b, 6), cols.ravel())), shape=(nb, 3 * na))
        vb = self.vol * self.b
        theta = sp.csr_matrix((self.dv, (self.i, b)), shape=(n, nb)) @ ext
        mean = sp.csr_matrix((self.wv * self.r / 3, (self.i, b)), shape=(n, nb)) @ ext
        m = np.bincount(self.i, self.wv * self.r ** 2 / 9, n)
        k = ext.T @ sp.diags(2 * vb[self.i] * self.wv) @ ext
        k = k + theta.T @ sp.diags(self.kappa * self.vol + 2 * vb * m) @ theta
        cross = theta.T @ sp.diags(2 * vb) @ mean
        return (k - cross - cross.T).tocsr()

    def static(self, held, u, f, implicit, order=1):
        """Minimises the energy less `f . u` over the real displacements not `held` (a mask of
        real dofs; `u` gives the held ones). Returns the real displacements and the reaction
        (the energy's gradient less `f`) on every real dof."""
        n3 = 3 * self.n
        k = self.hessian()
        if not implicit:
            ghosts = self.ghost_rows(False, order)[:, :n3]
            g = sp.vstack([sp.identity(n3, format="csr"), ghosts]).tocsr()
            if self.csrc is not None:
                rows = (3 * self.csrc[:, None] + np.arange(3)).ravel()
                image = -g[rows]
                if self.clamp == 2:
                    # A field zero on the face is odd there up to its even part `u_xx x^2 / 2`,
                    # which the odd image flips: add it back twice, `u_xx` from the quadratic
                    # fit over the real family of the point's real source.
                    real = np.concatenate([np.arange(self.n), self.src[self.n:]])[self.csrc]
                    at = (3 * real[:, None] + np.arange(3)).ravel()
                    image = image + sp.diags(np.repeat(self.depth ** 2, 3)) @ self.curvature()[at]
                g = sp.vstack([g, image]).tocsr()
            k = (g.T @ k @ g).tocsr()
            u = u.copy()
            free = ~held
            u[free] = solve(k[free][:, free], f[free] - k[free][:, held] @ u[held])
            return u, k @ u - f
        # Ghosts read their sources' whole families: the ghosts' displacements are unknowns
        # tied by `b u_all = 0`, solved with Lagrange multipliers.
        c = self.ghost_rows(True, order)
        ng = c.shape[0]
        b = (sp.hstack([sp.csr_matrix((ng, n3)), sp.identity(ng)]) - c).tocsr()
        free = np.concatenate([~held, np.ones(ng, bool)])
        hold = np.concatenate([held, np.zeros(ng, bool)])
        ua = np.concatenate([u, np.zeros(ng)])
        fa = np.concatenate([f, np.zeros(ng)])
        kkt = sp.bmat([[k[free][:, free], b[:, free].T], [b[:, free], None]]).tocsr()
        rhs = np.concatenate([fa[free] - k[free][:, hold] @ ua[hold], -(b[:, hold] @ ua[hold])])
        x = solve(kkt, rhs)
        ua[free] = x[: free.sum()]
        grad = k @ ua + b.T @ x[free.sum():] - fa
        return ua[:n3], grad[:n3]


def per_axis(rows, cols, vals, own_rows, own_cols, own_vals, shape):
    """The sparse matrix (`shape`) of a scalar combination applied to each of the three
    displacement components: `vals` at point `(rows, cols)` and `own_vals` at
    `(own_rows, own_cols)`, each point index `k` standing for the dofs `3 k + axis`."""
    r, c, v = [], [], []
    for ax in range(3):
        r += [3 * rows + ax, 3 * own_rows + ax]
        c += [3 * cols + ax, 3 * own_cols + ax]
        v += [vals, own_vals]
    return sp.csr_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))),
                         shape=shape)


def spread(model, order=1, implicit=False):
    """Prints the median, 99th percentile and largest of the correction's two factors and,
    with explicit ghosts, of each side ghost's extrapolation gain (the sum of its combination's
    coefficients' magnitudes: 1 would be a copy of its source)."""
    rows = model.ghost_rows(False, order)
    gains = [("dilatation factor", model.factors[0]), ("b factor", model.factors[1])]
    if rows.shape[0] and not implicit:
        gains.append(("ghost gain", np.asarray(abs(rows[::3]).sum(axis=1)).ravel()))
    for name, f in gains:
        print(f"  {name}: median {np.median(f):.2f}, 99% {np.percentile(f, 99):.2f}, "
              f"max {f.max():.2f}")


def cantilever(perifrac, n, unstructured, ghosts, implicit, order, image, tmp):
    """The bench's cantilever `n` cells across, clamped by the held layer (`image` 0) or a
    mirror image to first or second order (1, 2): the tip's error against P2, its sideways
    deflection over its vertical one, and the deflection curve's two parts (`curve`)."""
    nx = 10 * n
    h = 1.0 / nx
    held = 0 if image else math.ceil(K_HORIZON * KUHN_EDGE_PER_CELL)  # cells behind x = 0
    x, bary, vol, lam = mesh_box(perifrac, 1 + held * h, [nx + held, n, n], unstructured,
                                 os.path.join(tmp, "bar.mesh"))
    shift = np.array([held * h, 0.05, 0.05])
    x, bary = x - shift, bary - shift
    model = Model(bary, vol, lam, 0.3, x.min(0), x.max(0), ghosts, image)
    spread(model, order, implicit)
    f = np.zeros((len(vol), 3))
    f[:, 2] = -RHO * GRAVITY * vol
    u, _ = model.static(np.repeat(bary[:, 0] < 0, 3), np.zeros(3 * len(vol)), f.ravel(),
                        implicit, order)
    u = u.reshape(-1, 3)
    tip = bary[:, 0] > 1 - 2 * h
    at_end = [np.polyval(np.polyfit(bary[tip, 0], u[tip, a], 1), 1.0) for a in (1, 2)]
    return -at_end[1] / P2_TIP - 1, abs(at_end[0]) / -at_end[1], curve(bary, vol, u, h)


def curve(bary, vol, u, h):
    """Splits the bar's deflection into bending and the root's share. The volume-weighted mean
    deflection of each slab one cell long (particles binned by their x) beyond 0.2 m from the
    clamp is fitted as `scale w(x) + g x^2 + b + c x`, `w` Euler-Bernoulli's curve under the
    bar's weight: its quartic and cubic terms come from bending alone, so `scale - 1` is the
    bending compliance's error, while shear, the clamp's offset and rotation and any uniform
    change of curvature land in `g x^2 + b + c x`, returned at the tip over `w(1)` (the root's
    share). A converged P2
    answer (scikit-fem, 80 x 8 x 8 cells, scratch) sampled at the particles of the bars 3 to 6
    cells across gives both within 0.12% of zero (0.4% at 2 across)."""
    col = np.floor(bary[:, 0] / h).astype(int)
    real = col >= 0
    weight = np.bincount(col[real], vol[real])
    if not np.all(weight > 0):
        sys.exit("surface_study: a cell column holds no particle")
    xs = np.bincount(col[real], vol[real] * bary[real, 0]) / weight
    down = -np.bincount(col[real], vol[real] * u[real, 2]) / weight
    q, ei = RHO * GRAVITY * 0.01, E0 * 1e-4 / 12
    w = q * xs ** 2 * (6 - 4 * xs + xs ** 2) / (24 * ei)
    far = xs > 0.2
    terms = np.stack([w[far], xs[far] ** 2, np.ones(far.sum()), xs[far]], 1)
    scale, g, b, c = np.linalg.lstsq(terms, down[far], rcond=None)[0]
    return scale - 1, (g + b + c) / (q / (8 * ei))


def moduli(perifrac, nu, unstructured, ghosts, implicit, order, tmp):
    """The bench's tension bar at Poisson's ratio `nu`: E's relative error and nu measured."""
    n, nx, length = 8, 32, 0.4
    h = length / nx
    layer = math.ceil(K_HORIZON * KUHN_EDGE_PER_CELL)
    x, bary, vol, lam = mesh_box(perifrac, length + 2 * layer * h, [nx + 2 * layer, n, n],
                                 unstructured, os.path.join(tmp, "bar.mesh"))
    shift = np.array([layer * h, 0.05, 0.05])
    x, bary = x - shift, bary - shift
    model = Model(bary, vol, lam, nu, x.min(0), x.max(0), ghosts)
    pulled = bary[:, 0] > length
    held = np.repeat((bary[:, 0] < 0) | pulled, 3)
    strain = 1e-3
    u = np.zeros((len(vol), 3))
    u[pulled, 0] = strain * length
    u, grad = model.static(held, u.ravel(), np.zeros(3 * len(vol)), implicit, order)
    reaction = grad.reshape(-1, 3)[pulled, 0].sum()
    u = u.reshape(-1, 3)
    mid = (bary[:, 0] > length / 3) & (bary[:, 0] < 2 * length / 3)
    slope = [np.polyfit(bary[mid, a], u[mid, a], 1)[0] for a in range(3)]
    return reaction / 0.01 / slope[0] / E0 - 1, -(slope[1] + slope[2]) / 2 / slope[0]


def interior(perifrac, unstructured, tmp):
    """Over the moduli bar's particles more than a horizon from every face (whole families, no
    surface), nu = 0.3: the energy under an affine uniaxial stress over the continuum's, and
    under pure bending (curvature `kappa` about y, the exact linear field, quadratic in
    position) the energy density beyond the continuum's over `E kappa^2 delta^2` (the bending
    stiffness of the nonlocal model itself; see `bending_excess`)."""
    x, bary, vol, lam = mesh_box(perifrac, 0.4, [32, 8, 8], unstructured,
                                 os.path.join(tmp, "bar.mesh"))
    model = Model(bary, vol, lam, 0.3, x.min(0), x.max(0), False)
    delta = K_HORIZON * lam
    lo, hi = x.min(0), x.max(0)
    inner = np.all((bary - lo > delta) & (hi - bary > delta), axis=1)
    v = vol[inner]
    r = bary - (lo + hi) / 2
    u = r @ np.diag([1.0, -0.3, -0.3]) * 1e-3
    uniaxial = (v * model.energy_density(u)[inner]).sum() / (v.sum() * E0 * 1e-6 / 2)
    kappa, nu = 1e-2, 0.3
    rx, ry, rz = r.T
    u = np.stack([-kappa * rx * rz, nu * kappa * ry * rz,
                  kappa * (rx ** 2 + nu * (rz ** 2 - ry ** 2)) / 2], 1)
    excess = model.energy_density(u) - E0 * kappa ** 2 * rz ** 2 / 2
    bending = (v * excess[inner]).sum() / v.sum() / (E0 * kappa ** 2 * delta ** 2)
    return uniaxial, bending, inner.sum()


def bending_excess(nu):
    """The continuum limit of `interior`'s bending figure: pure bending's displacement is
    quadratic, so a bond of length r reads, beyond the linear strain, the extension
    `kappa r^2 n_z (nu - (1 + nu) n_x^2) / 2`, odd in the bond's direction, which the
    dilatation's symmetric fit does not see; the deviatoric term `b sum omega ed^2 V_j` stores its
    square, with `omega = delta / r` and `b = 15 mu / (2 pi delta^5)` integrated over the
    horizon ball: `(5 / 4) mu kappa^2 delta^2 <n_z^2 (nu - (1 + nu) n_x^2)^2>`, the mean over
    directions `nu^2 / 3 - 2 nu (1 + nu) / 15 + (1 + nu)^2 / 35`. Returned over
    `E kappa^2 delta^2`. A bar of square section H stores `E kappa^2 H^2 / 24` a unit volume
    in bending, so its bending stiffness is `1 + 24 bending_excess(nu) (delta / H)^2` times
    the continuum's (0.303 (delta / H)^2 at nu = 0.3)."""
    mean = nu ** 2 / 3 - 2 * nu * (1 + nu) / 15 + (1 + nu) ** 2 / 35
    return 1.25 / (2 * (1 + nu)) * mean


def main():
    """Parses the command line and prints one line per case run."""
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("case", choices=["cantilever", "moduli", "interior"], help="see above")
    ap.add_argument("--mesh", choices=["kuhn", "unstructured"], default="unstructured",
                    help="the bar's tets: Kuhn lattice or Delaunay of random points (seed 1)")
    ap.add_argument("--cells", type=int, nargs="+", default=[4], help="cells across (cantilever)")
    ap.add_argument("--nu", type=float, nargs="+", default=[0.3], help="Poisson's ratios (moduli)")
    ap.add_argument("--ghosts", action="store_true", help="mirror ghosts across the side faces")
    ap.add_argument("--implicit", action="store_true",
                    help="ghosts' gradients over their sources' whole families (implies --ghosts)")
    ap.add_argument("--order", type=int, choices=[1, 2], default=1,
                    help="ghosts extrapolated by an affine (1) or quadratic (2) least-squares fit")
    ap.add_argument("--clamp", choices=["held", "mirror", "mirror2"], default="held",
                    help="the cantilever's clamp: the bench's held layer behind x = 0, or the "
                    "bar mirrored across x = 0 moving as minus its source (zero on the face), "
                    "to first or second order")
    ap.add_argument("--perifrac", help="the perifrac binary (default: target/release's)",
                    default=os.path.join(os.path.dirname(__file__), "..", "target", "release",
                                         "perifrac"))
    a = ap.parse_args()
    if min(a.cells) < 1:
        ap.error("--cells: at least one cell across")
    if not all(-1 < nu < 0.5 for nu in a.nu):
        ap.error("--nu: Poisson's ratio must lie in (-1, 0.5)")
    given = set(arg.split("=")[0] for arg in sys.argv[1:])
    if a.case == "interior" and given & {"--ghosts", "--implicit", "--order"}:
        ap.error("interior takes no ghosts")
    if "--order" in given and not (a.ghosts or a.implicit):
        ap.error("--order shapes the ghosts: give --ghosts or --implicit")
    if a.case != "cantilever" and "--cells" in given:
        ap.error("--cells is the cantilever's")
    if a.case != "cantilever" and "--clamp" in given:
        ap.error("--clamp is the cantilever's")
    if a.implicit and a.clamp != "held":
        ap.error("--implicit takes the held clamp only")
    if a.case != "moduli" and "--nu" in given:
        ap.error("--nu is the moduli bar's")
    if not os.path.isfile(a.perifrac):
        ap.error(f"--perifrac: no file {a.perifrac}: build it with "
                 "`cargo build --release -p perifrac` or give its path")
    unstructured = a.mesh == "unstructured"
    ghosts = a.ghosts or a.implicit
    image = ["held", "mirror", "mirror2"].index(a.clamp)
    label = (f"{a.mesh}{' ghosts' if ghosts else ''}{' (implicit)' if a.implicit else ''}"
             f"{' (quadratic)' if ghosts and a.order == 2 else ''}"
             f"{['', ' mirror clamp', ' second-order mirror clamp'][image]}")
    with tempfile.TemporaryDirectory() as tmp:
        if a.case == "cantilever":
            for n in a.cells:
                err, side, (bend, root) = cantilever(a.perifrac, n, unstructured, ghosts,
                                                     a.implicit, a.order, image, tmp)
                print(f"{label} {10 * n}x{n}x{n}: tip {100 * err:+.2f}%, "
                      f"sideways {100 * side:.2f}% of vertical; bending {100 * bend:+.2f}%, "
                      f"root {100 * root:+.2f}% of the tip", flush=True)
        elif a.case == "interior":
            ratio, bending, count = interior(a.perifrac, unstructured, tmp)
            print(f"{a.mesh} 32x8x8, {count} particles a horizon from every face: "
                  f"uniaxial stress {ratio:.4f} of the continuum's energy; pure bending "
                  f"{bending:.5f} E kappa^2 delta^2 above it (continuum limit "
                  f"{bending_excess(0.3):.5f})")
        else:
            for nu in a.nu:
                de, got = moduli(a.perifrac, nu, unstructured, ghosts, a.implicit, a.order,
                                 tmp)
                print(f"{label} 32x8x8, nu {nu}: E {100 * de:+.2f}%, nu {got:.4f}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
