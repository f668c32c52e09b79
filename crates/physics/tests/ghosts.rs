//! Ghost particles across a body's faces (`ghost.rs`, issue 18): the ghosts follow every
//! affine field (and, fitted quadratically, every quadratic one); the forces stay the energy's
//! gradient and objective; completed families store the continuum's energy under a uniform
//! strain where the cut ones store more.

mod support;

use perifrac_physics::math::{mat_vec, rotation, Vec3};
use perifrac_physics::{
    ChenModel, ChenOptions, Discretization, FaceKind, ForceModel, GhostFaces, GhostFit, GhostLayer,
    GhostPlane, Ghosted, GHOST_GAIN_BOUND,
};
use perifrac_topology::mesher::{
    box_cut_data, mesh_surface, sphere_surface, BoxCut, MesherOptions,
};
use perifrac_topology::{BoundaryPlanes, TetMesh};
use support::{affine, forces, gradient_mismatch, nonuniform, norm_all, steel};

/// The box `[0, size]` of `cells` cells, unstructured (the bench's bars' mesh, seed 1) or
/// on the Kuhn lattice, horizon `k` mean edges.
fn box_disc(size: [f64; 3], cells: [usize; 3], k: f64, unstructured: bool) -> Discretization {
    if !unstructured {
        return support::block(size, cells, k).0;
    }
    support::mesh_disc(&box_mesh(size, cells), k)
}

/// `x` (m) under the uniform small strain `eps`: `y = (I + eps) x`.
fn strained(x: &[Vec3], eps: [[f64; 3]; 3]) -> Vec<Vec3> {
    let f = [
        [1.0 + eps[0][0], eps[0][1], eps[0][2]],
        [eps[1][0], 1.0 + eps[1][1], eps[1][2]],
        [eps[2][0], eps[2][1], 1.0 + eps[2][2]],
    ];
    affine(x, &f, [0.0; 3])
}

/// The unstructured tet mesh of the box `[0, size]` of `cells` cells (seed 1).
fn box_mesh(size: [f64; 3], cells: [usize; 3]) -> TetMesh {
    let (v, t) = box_cut_data([0.0; 3], size, cells, BoxCut::Unstructured(1)).expect("mesh");
    TetMesh::new(v, t).expect("box mesh").0
}

/// A shear, a pull with lateral contraction `nu` and a twist-like mixed strain, each of size
/// about `e`.
fn uniform_strains(e: f64, nu: f64) -> [(&'static str, [[f64; 3]; 3]); 3] {
    [
        ("shear", [[0.0, e, 0.0], [e, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        (
            "pull",
            [[e, 0.0, 0.0], [0.0, -nu * e, 0.0], [0.0, 0.0, -nu * e]],
        ),
        (
            "twist",
            [[0.0, 0.0, e], [0.0, 0.5 * e, -e], [e, -e, -0.5 * e]],
        ),
    ]
}

/// The six faces of the box `[0, size]`, all `kind`.
fn faces(size: [f64; 3], kind: FaceKind) -> Vec<GhostPlane> {
    GhostPlane::box_faces([0.0; 3], size)
        .into_iter()
        .map(|p| GhostPlane { kind, ..p })
        .collect()
}

fn ghosted(disc: Discretization, planes: &[GhostPlane], fit: GhostFit) -> Ghosted<ChenModel> {
    Ghosted::chen(disc, &[steel()], ChenOptions::default(), planes, fit).expect("ghosted model")
}

/// A list of planes, every one near every point (as `GhostLayer::build` takes them).
struct AllPlanes(Vec<GhostPlane>);

impl GhostFaces for AllPlanes {
    fn near(&self, _x: Vec3, _horizon: f64, out: &mut Vec<GhostPlane>) {
        out.extend_from_slice(&self.0);
    }
}

/// [`ghosted`] with the fits' gains bounded by `bound` instead of `GHOST_GAIN_BOUND`.
fn ghosted_bounded(
    disc: Discretization,
    planes: &[GhostPlane],
    fit: GhostFit,
    bound: f64,
) -> Ghosted<ChenModel> {
    let layer = GhostLayer::build_bounded(&disc, &AllPlanes(planes.to_vec()), fit, bound)
        .expect("ghost layer");
    Ghosted::chen_with_layer(disc, layer, &[steel()], ChenOptions::default())
        .expect("ghosted model")
}

/// The largest distance of a ghost from where `field` puts it, over the largest
/// displacement, when the real particles follow `field`.
fn ghost_miss(m: &Ghosted<ChenModel>, field: impl Fn(Vec3) -> Vec3) -> f64 {
    let ext = m.layer().extended().rest_positions();
    let n = m.layer().num_real();
    let y: Vec<Vec3> = ext[..n].iter().map(|&p| field(p)).collect();
    let mut out = vec![[0.0; 3]; ext.len()];
    m.layer().expand(&y, &mut out);
    let mut miss: f64 = 0.0;
    let mut size: f64 = 0.0;
    for (g, &p) in ext.iter().enumerate() {
        let want = field(p);
        let d = (0..3).map(|a| (out[g][a] - want[a]).powi(2)).sum::<f64>();
        let u = (0..3).map(|a| (want[a] - p[a]).powi(2)).sum::<f64>();
        miss = miss.max(d.sqrt());
        size = size.max(u.sqrt());
    }
    miss / size
}

#[test]
fn ghosts_follow_affine_fields_and_quadratic_ones_when_fitted_so() {
    let size = [0.06, 0.05, 0.04];
    let f = [
        [1.01, 0.02, -0.01],
        [0.005, 0.99, 0.03],
        [-0.02, 0.01, 1.02],
    ];
    let quad = |p: Vec3| {
        let a = affine(&[p], &f, [1e-3, 0.0, -2e-3])[0];
        [
            a[0] + 3.0 * p[1] * p[2],
            a[1] - 2.0 * p[0] * p[0],
            a[2] + p[1] * p[1],
        ]
    };
    let lin = |p: Vec3| affine(&[p], &f, [1e-3, 0.0, -2e-3])[0];
    for unstructured in [false, true] {
        let disc = box_disc(size, [6, 5, 4], 1.5, unstructured);
        let a = ghosted(disc.clone(), &faces(size, FaceKind::Free), GhostFit::Affine);
        // every quadratic fit kept (the corners' images take gains past the default bound)
        let q = ghosted_bounded(
            disc.clone(),
            &faces(size, FaceKind::Free),
            GhostFit::Quadratic,
            100.0,
        );
        let r = q.layer().report().clone();
        eprintln!(
            "unstructured {unstructured}: affine {:?}",
            a.layer().report()
        );
        eprintln!("unstructured {unstructured}: quadratic {r:?}");
        let (al, ql, qq) = (
            ghost_miss(&a, lin),
            ghost_miss(&q, lin),
            ghost_miss(&q, quad),
        );
        let aq = ghost_miss(&a, quad);
        eprintln!(
            "miss: affine/linear {al:e} quadratic/linear {ql:e} quadratic/quadratic {qq:e} \
             affine/quadratic {aq:e}"
        );
        // every source's family here fits both: no image dropped or fallen back
        assert_eq!((r.unfitted, r.affine_fallbacks), (0, 0));
        // exact fits, so only the rounding of positions of ~1e-2 m against displacements of
        // ~1e-3 m is left: measured up to 5.4e-14
        for miss in [al, ql, qq] {
            assert!(miss < 1e-12, "{miss}");
        }
        // the affine fit cannot follow a quadratic field: the check can fail
        assert!(aq > 1e-3, "{aq}");
        // the gains this block's images take, measured: affine largest 5.3 and 5.9, quadratic
        // 23.1 and 24.7 (the study's 40 x 4 x 4 bar: 6.8 and 35.9); twice that is a fault
        assert!(a.layer().report().gain.max < 12.0);
        assert!(r.gain.max < 50.0);
        // with the default bound the fits past it fall back to affine ones, which follow the
        // linear field still; none is dropped (affine gains are far under it). Measured: 24 of
        // 2,152 ghosts fall back on the lattice block, 18 of 2,186 on the unstructured one
        let d = ghosted(disc, &faces(size, FaceKind::Free), GhostFit::Quadratic);
        let rd = d.layer().report();
        eprintln!("unstructured {unstructured}: quadratic, default bound {rd:?}");
        assert_eq!((rd.ghosts, rd.unfitted), (r.ghosts, 0));
        assert!(rd.affine_fallbacks > 0 && rd.gain.max <= GHOST_GAIN_BOUND);
        assert!(ghost_miss(&d, lin) < 1e-12);
    }
}

#[test]
fn ghosted_forces_are_the_gradient_objective_and_vanish_at_rest() {
    let size = [0.04, 0.03, 0.03];
    for fit in [GhostFit::Affine, GhostFit::Quadratic] {
        let disc = box_disc(size, [4, 3, 3], 1.5, true);
        let mut m = ghosted(disc, &faces(size, FaceKind::Free), fit);
        let x = m.discretization().rest_positions().to_vec();
        let rest = forces(&mut m, &x);
        assert!(m.forces_vanish_at(&x));
        let y = nonuniform(&x, 0.01, 0.03);
        let f = forces(&mut m, &y);
        let worst = gradient_mismatch(&mut m, &y, &f, 1e-7 * 0.01, 7);
        let r = rotation([0.3, -0.5, 0.8], 0.9);
        let yr: Vec<Vec3> = y.iter().map(|&p| mat_vec(&r, p)).collect();
        let fr = forces(&mut m, &yr);
        let turned: Vec<Vec3> = f.iter().map(|&p| mat_vec(&r, p)).collect();
        let obj = support::diff_all(&fr, &turned) / norm_all(&f);
        let xr: Vec<Vec3> = x.iter().map(|&p| mat_vec(&r, p)).collect();
        let rigid = norm_all(&forces(&mut m, &xr)) / norm_all(&f);
        eprintln!(
            "{fit:?}: rest {:e} grad {worst:e} objectivity {obj:e} rigid {rigid:e}",
            norm_all(&rest)
        );
        // at rest the ghosts sit at their rest positions bit for bit: no force at all
        assert_eq!(norm_all(&rest), 0.0);
        // central differences of step 1e-9 m, as tests/fitted.rs (measured 3.2e-9, 1.8e-9)
        assert!(worst < 1e-5, "{worst}");
        // rounding of rotated lengths against 1% strains, as tests/fitted.rs (measured
        // 1.4e-13 and 1.2e-13 for both)
        assert!(obj < 1e-9 && rigid < 1e-9, "{obj} {rigid}");
    }
}

#[test]
fn completed_families_store_the_continuums_energy() {
    let size = [0.08, 0.08, 0.08];
    let (young, nu) = (200e9, 0.25);
    let (lam, mu) = (
        young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        young / (2.0 * (1.0 + nu)),
    );
    let e = 1e-5;
    let strains = [
        ("shear", [[0.0, e, 0.0], [e, 0.0, 0.0], [0.0, 0.0, 0.0]]),
        (
            "pull",
            [[e, 0.0, 0.0], [0.0, -nu * e, 0.0], [0.0, 0.0, -nu * e]],
        ),
        (
            "mixed",
            [[0.0, 0.0, e], [0.0, 0.5 * e, -e], [e, -e, -0.5 * e]],
        ),
    ];
    // the largest miss of the plain model on unstructured tets
    let mut worst_plain: f64 = 0.0;
    // the Kuhn lattice's whole families are soft in tension along its axes (docs/DECISIONS.md:
    // 0.947 of the continuum), so its rows are printed, not held to the continuum
    for unstructured in [false, true] {
        let disc = box_disc(size, [8, 8, 8], 1.5, unstructured);
        let vol: f64 = disc.volumes().iter().sum();
        let options = ChenOptions::default();
        let mut plain = ChenModel::with_options(disc.clone(), &[steel()], options).unwrap();
        let mut a = ghosted(disc.clone(), &faces(size, FaceKind::Free), GhostFit::Affine);
        let mut q = ghosted(disc, &faces(size, FaceKind::Free), GhostFit::Quadratic);
        let x = plain.discretization().rest_positions().to_vec();
        for (name, eps) in strains {
            let y = strained(&x, eps);
            let tr = eps[0][0] + eps[1][1] + eps[2][2];
            let ee: f64 = eps.iter().flatten().map(|v| v * v).sum();
            let w = vol * (lam * tr * tr / 2.0 + mu * ee);
            let (p, ga, gq) = (
                plain.elastic_energy(&y) / w,
                a.elastic_energy(&y) / w,
                q.elastic_energy(&y) / w,
            );
            eprintln!(
                "unstructured {unstructured} {name}: plain {p:.4} affine {ga:.4} \
                 quadratic {gq:.4}"
            );
            // an affine field puts both fits' ghosts in the same place, to the rounding of the
            // fits (ghost positions to 5e-14 of the displacement, above): the energies agree to
            // 1e-9 of themselves or better
            assert!((ga - gq).abs() < 1e-9, "{ga} {gq}");
            if unstructured {
                // whole families on unstructured tets store the continuum's energy (the
                // study's interior: 1.001): measured 0.9981 to 1.0005 with ghosts, the cut
                // families 0.9702 to 1.0340 without
                assert!((ga - 1.0).abs() < 0.005, "{name}: {ga}");
                worst_plain = worst_plain.max((p - 1.0).abs());
            }
        }
    }
    assert!(worst_plain > 0.02, "{worst_plain}");
}

#[test]
fn a_clamped_face_holds_its_images_at_minus_their_sources() {
    let size = [0.06, 0.03, 0.03];
    let mut planes = faces(size, FaceKind::Free);
    planes[0].kind = FaceKind::Clamped; // x = 0
    let disc = box_disc(size, [6, 3, 3], 1.5, true);
    let m = ghosted(disc, &planes, GhostFit::Affine);
    // a field that vanishes on x = 0 and is linear in x is odd across it, and affine: every
    // ghost, the clamp's images of the free faces' ghosts included, follows it exactly
    let odd = |p: Vec3| [p[0] * 1.02, p[1] + 0.03 * p[0], p[2] - 0.01 * p[0]];
    let miss = ghost_miss(&m, odd);
    eprintln!("clamped: {:?}, miss {miss:e}", m.layer().report());
    assert!(miss < 1e-12, "{miss}");
    // a rigid shift is not odd: the clamp's images move against it
    let shift = |p: Vec3| [p[0], p[1] + 1e-3, p[2]];
    assert!(ghost_miss(&m, shift) > 0.5);
}

#[test]
fn ghosts_refuse_a_plane_without_a_normal() {
    let size = [0.03, 0.03, 0.03];
    let disc = box_disc(size, [3, 3, 3], 1.5, true);
    let mut bad = faces(size, FaceKind::Free);
    bad[2].normal = [0.0; 3];
    let err = Ghosted::chen(
        disc,
        &[steel()],
        ChenOptions::default(),
        &bad,
        GhostFit::Affine,
    )
    .expect_err("a zero normal is refused");
    assert!(err.to_string().contains("ghost plane 2"), "{err}");
}

/// A mesh's boundary as ghost faces: its planes near a point (free) and its inside.
struct MeshFaces(BoundaryPlanes);

impl GhostFaces for MeshFaces {
    fn near(&self, x: Vec3, horizon: f64, out: &mut Vec<GhostPlane>) {
        out.extend(
            self.0
                .near(x, horizon)
                .into_iter()
                .map(|(point, normal)| GhostPlane {
                    point,
                    normal,
                    kind: FaceKind::Free,
                }),
        );
    }

    fn inside(&self, x: Vec3) -> bool {
        self.0.inside(x)
    }
}

/// The energy of `m` under the uniform strain `eps` (symmetric, small) over the continuum's.
fn energy_ratio<M: ForceModel>(m: &mut M, eps: [[f64; 3]; 3]) -> f64 {
    let (young, nu) = (200e9, 0.25);
    let (lam, mu) = (
        young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
        young / (2.0 * (1.0 + nu)),
    );
    let x = m.discretization().rest_positions().to_vec();
    let vol: f64 = m.discretization().volumes().iter().sum();
    let tr = eps[0][0] + eps[1][1] + eps[2][2];
    let ee: f64 = eps.iter().flatten().map(|v| v * v).sum();
    m.elastic_energy(&strained(&x, eps)) / (vol * (lam * tr * tr / 2.0 + mu * ee))
}

#[test]
fn a_meshs_boundary_gives_the_boxs_planes_and_a_spheres_tangent_planes() {
    let [shear, pull, _] = uniform_strains(1e-5, 0.25);
    let strains = [shear, pull];
    // a box: the boundary's planes are the box's six, edges and corners included
    let size = [0.06, 0.05, 0.04];
    let mesh = box_mesh(size, [6, 5, 4]);
    let disc = support::mesh_disc(&mesh, 1.5);
    let boundary = MeshFaces(BoundaryPlanes::new(&mesh, disc.horizon()));
    let from_mesh = GhostLayer::build_with(&disc, &boundary, GhostFit::Affine).unwrap();
    let from_planes =
        GhostLayer::build(&disc, &faces(size, FaceKind::Free), GhostFit::Affine).unwrap();
    eprintln!("box: mesh {:?}", from_mesh.report());
    eprintln!("box: planes {:?}", from_planes.report());
    let options = ChenOptions::default();
    let mut a = Ghosted::chen_with_layer(disc.clone(), from_mesh, &[steel()], options).unwrap();
    let mut b = Ghosted::chen_with_layer(disc, from_planes, &[steel()], options).unwrap();
    // the same images (an edge particle's may come in another order, nearest face first):
    // the same counts and gains, and the same energy to the bit (measured)
    assert_eq!(a.layer().report(), b.layer().report());
    for (name, eps) in strains {
        let (ra, rb) = (energy_ratio(&mut a, eps), energy_ratio(&mut b, eps));
        eprintln!("box {name}: mesh faces {ra:.5}, planes {rb:.5}");
        assert_eq!(ra, rb, "{name}");
    }
    // a sphere meshed from its surface: tangent planes, no image inside the body
    let (sv, sf) = sphere_surface(0.05, 24);
    let opts = MesherOptions {
        edge_length: None,
        resolution: Some(10),
    };
    let out = mesh_surface(&sv, &sf, &opts).unwrap();
    let (mesh, _) = TetMesh::new(out.vertices, out.tets).unwrap();
    let disc = support::mesh_disc(&mesh, 1.5);
    let planes = BoundaryPlanes::new(&mesh, disc.horizon());
    let boundary = MeshFaces(planes.clone());
    let layer = GhostLayer::build_with(&disc, &boundary, GhostFit::Affine).unwrap();
    eprintln!("sphere: {} particles, {:?}", disc.len(), layer.report());
    let delta = disc.horizon();
    let near = disc
        .rest_positions()
        .iter()
        .filter(|&&x| !planes.near(x, delta).is_empty())
        .count();
    let mut hist = [0usize; 5];
    for &x in disc.rest_positions() {
        hist[planes.near(x, delta).len().min(4)] += 1;
    }
    eprintln!("planes per particle: {hist:?}");
    // the smoothed normals make the faceted sphere one tangent plane wherever a particle is
    // (unsmoothed facets, 30 degrees apart at most: 19,467 images, up to seven a particle)
    assert_eq!(hist[2..], [0, 0, 0]);
    let mut plain = ChenModel::with_options(disc.clone(), &[steel()], options).unwrap();
    let mut ghosted = Ghosted::chen_with_layer(disc, layer, &[steel()], options).unwrap();
    for (name, eps) in strains {
        let (p, g) = (
            energy_ratio(&mut plain, eps),
            energy_ratio(&mut ghosted, eps),
        );
        eprintln!("sphere {name}: plain {p:.5}, ghosts {g:.5}");
    }
    eprintln!("sphere: particles within a horizon of the boundary {near}");
    // one image a near-surface particle at most (measured: 3,845 kept and 120 without a real
    // particle within a horizon, of 3,965)
    let r = ghosted.layer().report();
    assert!(
        r.ghosts + r.unbonded <= near,
        "{} + {} > {near}",
        r.ghosts,
        r.unbonded
    );
    // The energies are printed, not held to the continuum: the mesher's body-centred cubic
    // interior is itself anisotropic (at resolution 16 the sphere stores 0.970 and 1.037 of the
    // continuum's energy under these strains with or without ghosts, more off than at 10), so
    // the surface is not what a sphere's figure measures.
}

#[test]
fn a_bar_thinner_than_a_horizon_is_mirrored_across_each_side_and_its_edges_not_through_itself() {
    // 2 cells across at k = 1.5: every particle is within a horizon of all four side faces
    let size = [0.1, 0.02, 0.02];
    let disc = box_disc(size, [10, 2, 2], 1.5, true);
    let planes = faces(size, FaceKind::Free);
    let layer = GhostLayer::build(&disc, &planes, GhostFit::Affine).unwrap();
    let r = layer.report();
    // the images expected, counted here on their own: for each particle, every set of up to
    // three near faces with no two opposite (a bar's two sides composed would be a
    // translation of the bar across itself, not an image)
    let delta = disc.horizon();
    let mut expected = 0;
    for &x in disc.rest_positions() {
        let near: Vec<&GhostPlane> = planes
            .iter()
            .filter(|p| {
                let d: f64 = (0..3).map(|a| (p.point[a] - x[a]) * p.normal[a]).sum();
                d > 0.0 && d < delta
            })
            .collect();
        for set in 1u32..1 << near.len() {
            let m: Vec<_> = (0..near.len()).filter(|b| set & (1 << b) != 0).collect();
            let opposed = m.iter().any(|&a| {
                m.iter().any(|&b| {
                    (0..3)
                        .map(|k| near[a].normal[k] * near[b].normal[k])
                        .sum::<f64>()
                        < -0.5
                })
            });
            if m.len() <= 3 && !opposed {
                expected += 1;
            }
        }
    }
    eprintln!(
        "thin bar: {} particles, {expected} images expected, {r:?}",
        disc.len()
    );
    assert_eq!(r.ghosts + r.unbonded + r.unfitted, expected);
    // and they follow affine fields, so the bar keeps its energy objective and exact
    let m = ghosted(disc, &planes, GhostFit::Affine);
    let f = [[1.01, 0.02, 0.0], [0.0, 0.99, 0.01], [0.0, 0.0, 1.0]];
    let miss = ghost_miss(&m, |p| affine(&[p], &f, [0.0; 3])[0]);
    assert!(miss < 1e-12, "{miss}");
}

#[test]
fn ghosted_dilatation_reads_no_volume_change_in_a_shear() {
    // issue 18: a correction must not read shear as volume change. With ghosts the fitted
    // dilatation runs over completed families whose ghosts follow every affine field, so each
    // real particle's theta is tr(eps) under any uniform strain, on a box's faces, edges and
    // corners and on a sphere's faceted surface alike, with either fit.
    let e = 1e-6;
    let strains = uniform_strains(e, 0.3);
    let cube = box_mesh([0.04, 0.03, 0.02], [4, 3, 2]);
    let (sv, sf) = sphere_surface(0.05, 16);
    let opts = MesherOptions {
        edge_length: None,
        resolution: Some(6),
    };
    let out = mesh_surface(&sv, &sf, &opts).expect("sphere mesh");
    let (sphere, _) = TetMesh::new(out.vertices, out.tets).expect("sphere mesh");
    for (body, mesh) in [("box", &cube), ("sphere", &sphere)] {
        let disc = support::mesh_disc(mesh, 1.5);
        let boundary = MeshFaces(BoundaryPlanes::new(mesh, disc.horizon()));
        for fit in [GhostFit::Affine, GhostFit::Quadratic] {
            let layer = GhostLayer::build_with(&disc, &boundary, fit).expect("layer");
            assert!(layer.num_ghosts() > 0);
            let mut m =
                Ghosted::chen_with_layer(disc.clone(), layer, &[steel()], ChenOptions::default())
                    .expect("model");
            let mut plain =
                ChenModel::with_options(disc.clone(), &[steel()], ChenOptions::default())
                    .expect("model");
            let x = disc.rest_positions().to_vec();
            let n = x.len();
            for (name, eps) in strains {
                let y = strained(&x, eps);
                let _ = forces(&mut m, &y);
                let _ = forces(&mut plain, &y);
                let tr = eps[0][0] + eps[1][1] + eps[2][2];
                let size = eps.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
                let worst =
                    |th: &[f64]| th[..n].iter().map(|t| (t - tr).abs()).fold(0.0, f64::max) / size;
                let (g, p) = (worst(&m.inner().dilatations()), worst(&plain.dilatations()));
                eprintln!(
                    "{body} {fit:?} {name}: |theta - tr eps| / |eps| ghosts {g:.2e}, \
                     fitted without {p:.2e}"
                );
                // As the fitted dilatation's own test: extensions of ~1e-6 r read to the
                // linearisation of |F X| (relative ~1e-6) and the rounding of lengths; the
                // fitted correction without ghosts is exact too, so both are held to it.
                assert!(g < 2e-5, "{body} {fit:?} {name}: {g}");
                assert!(p < 2e-5, "{body} {name}: {p}");
            }
        }
    }
}

#[test]
fn a_ghost_never_bonds_closer_than_half_a_real_bond() {
    // A face just under a particle puts its image beside it: a bond that short is stiffer
    // than any the mesh has (as 1 / r^3) and set the stable step (30 times shorter than the
    // fitted correction's on bunny.mesh, whose slivers put barycentres a hair from the
    // surface). Here a plane 1e-5 m under the lowest barycentre of an unstructured block.
    let size = [0.04, 0.03, 0.02];
    let disc = box_disc(size, [4, 3, 2], 1.5, true);
    let x = disc.rest_positions();
    let low = x.iter().map(|p| p[2]).fold(f64::INFINITY, f64::min);
    let plane = GhostPlane {
        point: [0.0, 0.0, low - 1e-5],
        normal: [0.0, 0.0, -1.0],
        kind: FaceKind::Free,
    };
    for fit in [GhostFit::Affine, GhostFit::Quadratic] {
        let layer = GhostLayer::build(&disc, &[plane], fit).expect("layer");
        let r = layer.report().clone();
        eprintln!("{fit:?}: {r:?}");
        // the lowest particle's own image at 2e-5 m at least
        assert!(r.short >= 2, "{r:?}");
        let (fam, ext) = (disc.family(), layer.extended());
        let n = layer.num_real();
        let ef = ext.family();
        for i in 0..n {
            let shortest = fam.rest_lengths()[fam.range(i)]
                .iter()
                .fold(f64::INFINITY, |a, &b| a.min(b));
            for k in ef.range(i) {
                if ef.neighbours()[k] as usize >= n {
                    assert!(
                        ef.rest_lengths()[k] >= 0.5 * shortest,
                        "particle {i}: ghost bond {} against {shortest}",
                        ef.rest_lengths()[k]
                    );
                }
            }
        }
        // and the forces stay the energy's gradient with the bond left out
        let mut m =
            Ghosted::chen_with_layer(disc.clone(), layer, &[steel()], ChenOptions::default())
                .expect("model");
        let y = nonuniform(x, 0.01, 0.03);
        let f = forces(&mut m, &y);
        let worst = gradient_mismatch(&mut m, &y, &f, 1e-7 * 0.01, 7);
        eprintln!("{fit:?}: max |f + dE/dy| / max |f| = {worst:e}");
        // as the other gradient tests here (measured 3.2e-9 on the six-face block)
        assert!(worst < 1e-6, "{worst}");
    }
}
