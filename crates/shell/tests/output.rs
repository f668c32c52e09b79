//! Frames for output: the sheet as it is, and pieces given a thickness.

use std::collections::HashMap;

use perifrac_physics::math::{cross, dot, norm, sub};
use perifrac_shell::generate::sheet;
use perifrac_shell::*;

/// Every directed edge once and every undirected edge twice: a closed, consistently oriented
/// surface.
fn closed(m: &FrameMesh) -> bool {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &m.triangles {
        for k in 0..3 {
            *directed.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    directed
        .iter()
        .all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1))
}

#[test]
fn a_thick_frame_of_a_broken_sheet_is_closed_with_the_pieces_volume_and_crack_walls() {
    // The pulled sheet of the fracture tests, broken in two: each piece as a 1 mm slab must be
    // closed and right side out, their volumes adding up to area x thickness (the sheet is
    // flat, so to round-off), and the walls along the crack flagged.
    let s = sheet(0.1, 0.05, 20, 10).unwrap();
    let mesh = ShellMesh::new(s.vertices.clone(), s.triangles.clone()).unwrap();
    let glass = ShellMaterial::new(70e9, 0.22, 2500.0, 1e-3).unwrap();
    let model = ShellModel::new(mesh, glass)
        .unwrap()
        .with_fracture(ShellFracture::new(1e-3, 1e-3, 0.25, 1.0).unwrap());
    let mut shell = ShellDynamics::new(model).unwrap();
    for (i, p) in s.vertices.iter().enumerate() {
        if p[0] < 1e-9 {
            shell.drive(i, [-1.0, 0.0, 0.0]);
        } else if p[0] > 0.1 - 1e-9 {
            shell.drive(i, [1.0, 0.0, 0.0]);
        }
    }
    let dt = 0.25 * shell.stable_step().unwrap();
    let mut steps = 0;
    while pieces(shell.model().mesh()).iter().max() == Some(&0) && steps < 20_000 {
        shell.step(dt).unwrap();
        shell.fracture().unwrap();
        steps += 1;
    }
    let m = shell.model();
    let thin = m.frame(shell.positions(), shell.velocities(), None);
    assert_eq!(thin.triangles.len(), m.mesh().triangles().len());
    let thick = m.frame(shell.positions(), shell.velocities(), Some(1e-3));
    assert!(closed(&thick));
    // Unit normals (to round-off) on the side each triangle faces, the lower sheet's the upper
    // one's turned over; both sheets move with the mid-surface.
    let nv = shell.positions().len();
    assert_eq!((thin.normals.len(), thin.velocities.len()), (nv, nv));
    assert_eq!(
        (thick.normals.len(), thick.velocities.len()),
        (2 * nv, 2 * nv)
    );
    for i in 0..nv {
        let [a, b] = [thick.normals[i], thick.normals[i + nv]];
        assert!((norm(a) - 1.0).abs() < 1e-12, "{a:?}");
        assert_eq!(b, [-a[0], -a[1], -a[2]]);
        assert_eq!(thick.velocities[i], shell.velocities()[i]);
        assert_eq!(thick.velocities[i + nv], shell.velocities()[i]);
    }
    for t in &thin.triangles {
        let [a, b, c] = t.map(|i| shell.positions()[i as usize]);
        let face = cross(sub(b, a), sub(c, a));
        for &i in t {
            assert!(dot(thin.normals[i as usize], face) > 0.0);
        }
    }
    let n = *thick.piece.iter().max().unwrap() as usize + 1;
    assert!(n >= 2);
    // The pieces' mid-surface area at the current positions, times the thickness.
    let area: f64 = m
        .mesh()
        .triangles()
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| shell.positions()[i as usize]);
            let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let cz = e1[0] * e2[1] - e1[1] * e2[0];
            let cx = e1[1] * e2[2] - e1[2] * e2[1];
            let cy = e1[2] * e2[0] - e1[0] * e2[2];
            0.5 * (cx * cx + cy * cy + cz * cz).sqrt()
        })
        .sum();
    let volume = enclosed_volume(&thick.vertices, &thick.triangles);
    // Offsets along vertex normals of a sheet that stays nearly flat (it is pulled in its
    // plane): volume = area x thickness to 1e-6 (measured below).
    eprintln!(
        "{n} pieces after {steps} steps; volume {volume:.6e} m^3 against {:.6e}, {:.1e} apart",
        area * 1e-3,
        (volume - area * 1e-3).abs() / (area * 1e-3)
    );
    assert!((volume - area * 1e-3).abs() < 1e-6 * area * 1e-3);
    let walls = thick.crack.iter().filter(|&&c| c == 1).count();
    assert!(walls > 0);
}
