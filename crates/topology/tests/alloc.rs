//! Split, crack and advect allocate nothing in steady state (a counting global allocator).

mod common;

use common::interior_faces;
use perifrac_topology::primitives;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn count<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let r = f();
    (r, ALLOCATIONS.load(Ordering::Relaxed) - before)
}

// Single test in this binary, so no other test thread allocates while we count.
#[test]
fn steady_state_split_crack_and_advect_do_not_allocate() {
    let mut m = primitives::box_mesh([0.0; 3], [1.0; 3], [6, 6, 6]);
    let faces = interior_faces(&m);
    // Warm-up: a first batch of cracks and a split sizes the scratch buffers.
    for &(t, f) in faces.iter().step_by(7) {
        m.crack_face(t, f).unwrap();
    }
    m.split();
    let n = m.num_tets();
    let (mass, vel) = (vec![1.0; n], vec![[1.0, 0.0, 0.0]; n]);
    m.advect(0.1, &mass, &vel);
    // A second, smaller batch. Growth of the vertex arrays is the one allocation allowed.
    let batch: Vec<_> = faces.iter().skip(3).step_by(97).copied().collect();
    let (_, cracks) = count(|| {
        for &(t, f) in &batch {
            let _ = m.crack_face(t, f);
        }
    });
    assert_eq!(cracks, 0, "crack_face allocated");
    let vertices_before = m.num_vertices();
    let (report, splits) = count(|| m.split());
    if report.copies_added == 0 {
        assert_eq!(splits, 0, "split allocated without adding copies");
    } else {
        // Only the vertex arrays may grow: positions, origins and the queue marks.
        assert!(splits <= 3, "split made {splits} allocations");
        assert!(m.num_vertices() > vertices_before);
    }
    // The first advect after new copies may grow its per-vertex accumulator; the next may not.
    m.advect(0.1, &mass, &vel);
    let (_, advects) = count(|| m.advect(0.1, &mass, &vel));
    assert_eq!(advects, 0, "advect allocated");
}
