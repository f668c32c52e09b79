//! Self-contact allocates nothing per evaluation once its buffers fit, list rebuilds included.
//! Its own test binary: the counting allocator sees every thread of the process.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use perifrac_shell::generate::sheet;
use perifrac_shell::*;

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn evaluations_allocate_nothing_after_warm_up() {
    // Two 4 x 4 cm sheets of 16 x 16 quads, 1 cm apart at rest, the upper one sliding over
    // the lower at 0.3 mm: every evaluation finds pairs, and each 0.4 mm slide (past half the
    // skin from the mean move, the lower sheet standing) rebuilds the list.
    let s = sheet(0.04, 0.04, 16, 16).unwrap();
    let nv = s.vertices.len();
    let mut v = s.vertices.clone();
    v.extend(s.vertices.iter().map(|p| [p[0], p[1], 0.01]));
    let mut t = s.triangles.clone();
    t.extend(s.triangles.iter().map(|t| t.map(|i| i + nv as u32)));
    let mesh = ShellMesh::new(v, t).unwrap();
    let steel = ShellMaterial::new(200e9, 0.3, 7800.0, 1e-3).unwrap();
    let mut sc = SelfContact::new(ShellSelfContact::default(), &steel).unwrap();
    let mut x = mesh.vertices().to_vec();
    let mut f = vec![[0.0; 3]; x.len()];
    let mut evaluate = |k: usize, x: &mut Vec<[f64; 3]>, f: &mut Vec<[f64; 3]>| {
        for (i, p) in x[nv..].iter_mut().enumerate() {
            *p = [
                s.vertices[i][0] + 4e-4 * (k % 7) as f64,
                s.vertices[i][1],
                3e-4,
            ];
        }
        sc.add_forces(&mesh, x, f).unwrap();
        sc.stats()
    };
    // Inside a pool of two: called from outside any pool, rayon's injection of the work from
    // this thread allocated twice in 40 evaluations (its own, not self-contact's; 0 in a pool
    // of one thread or two).
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let (builds, pairs) = pool.install(|| {
        for k in 0..20 {
            evaluate(k, &mut x, &mut f);
        }
        COUNTING.store(true, Ordering::SeqCst);
        let mut builds = 0;
        let mut pairs = usize::MAX;
        for k in 0..40 {
            let st = evaluate(k, &mut x, &mut f);
            builds += st.rebuilt as usize;
            pairs = pairs.min(st.vertex_face + st.edge_edge);
        }
        COUNTING.store(false, Ordering::SeqCst);
        (builds, pairs)
    });
    let count = ALLOCATIONS.load(Ordering::SeqCst);
    eprintln!(
        "{builds} rebuilds in 40 evaluations, at least {pairs} pairs each, {count} allocations"
    );
    assert!(builds > 20 && pairs > 100);
    assert_eq!(count, 0);
}
