//! The counting allocator counts this thread's allocations and
//! reallocations inside the window, and nothing else.

use echothigh_testkit::{count_allocations, CountingAllocator};
use std::hint::black_box;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

#[test]
fn counts_this_threads_allocations_in_the_window_only() {
    let ((), n) = count_allocations(|| {});
    assert_eq!(n, 0);
    let (v, n) = count_allocations(|| black_box(vec![1u8; 8]));
    assert_eq!(n, 1);
    // Growing past the capacity reallocates: counted.
    let (v, n) = count_allocations(move || {
        let mut v = v;
        v.reserve_exact(1024);
        black_box(v)
    });
    assert_eq!(n, 1);
    // Freeing is not an allocation.
    let ((), n) = count_allocations(move || drop(v));
    assert_eq!(n, 0);
    // Another thread's allocations are not this thread's.
    let other = std::thread::spawn(|| black_box(vec![0u64; 64]).len());
    let ((), n) = count_allocations(|| std::thread::sleep(std::time::Duration::from_millis(5)));
    assert_eq!(other.join().unwrap(), 64);
    assert_eq!(n, 0);
    // Nested windows both see the inner allocation.
    let ((), outer) = count_allocations(|| {
        let ((), inner) = count_allocations(|| drop(black_box(Box::new(1u32))));
        assert_eq!(inner, 1);
    });
    assert!(outer >= 1);
}
