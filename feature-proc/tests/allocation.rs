//! Once its buffers have grown to the scans' size, extraction allocates nothing.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

mod common;

use common::recorded::scan_input;
use feature_proc::{Extractor, FeatureConfig};
use test_data::seed_hall_scans;

/// Counts every allocation of this test binary (it holds one test, so nothing else runs).
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards every call unchanged to the system allocator.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller's contract is passed on unchanged.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn the_hot_path_does_not_allocate() {
    let scans = seed_hall_scans();
    let mut extractor = Extractor::new(FeatureConfig::default());
    let mut corners = 0;
    // The first pass grows the buffers to the largest scan.
    for scan in &scans {
        corners += extractor
            .extract(&scan_input(scan))
            .map_or(0, |f| f.corners.len());
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for scan in &scans {
        corners += extractor
            .extract(&scan_input(scan))
            .map_or(0, |f| f.corners.len());
    }
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert!(corners > 0);
    assert_eq!(allocations, 0, "{allocations} allocations in 400 scans");
}
