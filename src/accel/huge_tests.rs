//! Tests of [`HugeVec`]: every operation agrees with a `Vec`'s on every backing, and
//! large arrays get a 2 MiB-aligned mapping.

use super::*;

/// A 48-byte element (not a power of two) with distinct contents per index.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct Item {
    a: [u32; 4],
    b: [f32; 8],
}

fn item(i: usize) -> Item {
    Item {
        a: [i as u32, !(i as u32), 7, i as u32 * 3],
        b: [i as f32 * 0.5; 8],
    }
}

/// Elements for at least `bytes` bytes.
fn count_for(bytes: usize) -> usize {
    bytes.div_ceil(size_of::<Item>())
}

/// Pushes, extends, indexes, writes, clones and compares `n` items on `backing`,
/// starting from capacity `cap`, each step checked against a `Vec` doing the same.
fn agrees_with_vec(n: usize, cap: usize, backing: Backing) -> HugeVec<Item> {
    let mut huge = HugeVec::with_backing(cap, backing);
    let mut vec = Vec::with_capacity(cap);
    assert!(huge.is_empty());
    assert_eq!(huge, vec);
    for i in 0..n / 2 {
        huge.push(item(i));
        vec.push(item(i));
        assert_eq!(huge.len(), vec.len());
        assert_eq!(huge[i], vec[i]);
    }
    let rest: Vec<Item> = (n / 2..n).map(item).collect();
    huge.extend_from_slice(&rest);
    vec.extend_from_slice(&rest);
    assert_eq!(huge, vec);
    assert!(huge.capacity() >= huge.len());
    if n > 0 {
        huge[n / 3].a[2] = 99;
        vec[n / 3].a[2] = 99;
        huge.last_mut().unwrap().b[0] = -1.0;
        vec.last_mut().unwrap().b[0] = -1.0;
    }
    assert_eq!(huge, vec);
    assert_eq!(format!("{huge:?}"), format!("{vec:?}"));
    let copy = huge.clone();
    assert_eq!(copy, huge);
    if backing != Backing::Auto {
        assert_eq!(copy.is_mapped(), huge.is_mapped());
    }
    huge.shrink_to_fit();
    assert_eq!(huge, vec);
    huge
}

#[test]
fn empty_small_and_large_arrays_behave_like_a_vec_on_every_backing() {
    let large = count_for(3 * MIN_MAPPED_BYTES) + 5;
    for backing in [Backing::Auto, Backing::Heap, Backing::Mapped] {
        for (n, cap) in [
            (0, 0),
            (1, 0),
            (10, 3),
            (1000, 1000),
            (large, 0),
            (large, large),
        ] {
            agrees_with_vec(n, cap, backing);
        }
    }
}

#[test]
fn large_arrays_are_mapped_on_a_huge_page_boundary_and_small_ones_are_not() {
    let small = agrees_with_vec(1000, 1000, Backing::Auto);
    assert!(!small.is_mapped());
    // Grown past the threshold by pushes, and reserved large from the start.
    let large = count_for(3 * MIN_MAPPED_BYTES);
    for cap in [0, large] {
        let v = agrees_with_vec(large, cap, Backing::Auto);
        assert!(v.is_mapped(), "capacity {cap}");
        assert_eq!(v.as_ptr() as usize % HUGE_PAGE, 0);
        // Whole huge pages (the alignment slack among them), at most twice the room
        // the array needed plus one for the slack.
        let used = v.len() * size_of::<Item>();
        assert!(v.reserved_bytes() >= used);
        assert!(v.reserved_bytes() <= (2 * used).next_multiple_of(HUGE_PAGE) + HUGE_PAGE);
        assert_eq!(v.reserved_bytes() % HUGE_PAGE, 0);
        assert!(v.clone().is_mapped());
    }
    let heap = agrees_with_vec(large, 0, Backing::Heap);
    assert!(!heap.is_mapped());
    assert!(!heap.clone().is_mapped());
    let forced = agrees_with_vec(3, 0, Backing::Mapped);
    assert!(forced.is_mapped());
    assert_eq!(forced.as_ptr() as usize % HUGE_PAGE, 0);
}

#[test]
fn zeroed_arrays_hold_zeros_and_take_their_backing() {
    let zero = Item {
        a: [0; 4],
        b: [0.0; 8],
    };
    for n in [0, 1, 1000, count_for(MIN_MAPPED_BYTES)] {
        for backing in [Backing::Auto, Backing::Heap, Backing::Mapped] {
            let mut v = HugeVec::<Item>::zeroed(n, backing);
            assert_eq!(v.len(), n, "{n} items, {backing:?}");
            assert!(v.iter().all(|x| *x == zero), "{n} items, {backing:?}");
            let mapped = backing == Backing::Mapped
                || (backing == Backing::Auto && n * size_of::<Item>() >= MIN_MAPPED_BYTES);
            assert_eq!(v.is_mapped(), mapped, "{n} items, {backing:?}");
            // Still growable like any other.
            v.push(item(n));
            assert_eq!(v[n], item(n));
        }
    }
}

#[test]
fn truncate_keeps_the_front_on_every_backing() {
    for n in [10, count_for(MIN_MAPPED_BYTES)] {
        let items: Vec<Item> = (0..n).map(item).collect();
        for backing in [Backing::Auto, Backing::Heap, Backing::Mapped] {
            let mut v = HugeVec::from_slice(&items, backing);
            v.truncate(n + 1);
            assert_eq!(
                v, items,
                "{n} items, {backing:?}: a longer length keeps all"
            );
            v.truncate(n / 2);
            assert_eq!(v.as_slice(), &items[..n / 2], "{n} items, {backing:?}");
            // The slots past the new end are free again.
            v.push(item(n));
            assert_eq!(v.len(), n / 2 + 1, "{n} items, {backing:?}");
            assert_eq!(v[n / 2], item(n), "{n} items, {backing:?}");
        }
    }
}

#[test]
fn a_vec_converts_by_its_size() {
    let small: HugeVec<Item> = (0..100).map(item).collect::<Vec<_>>().into();
    assert!(!small.is_mapped());
    let n = count_for(MIN_MAPPED_BYTES);
    let items: Vec<Item> = (0..n).map(item).collect();
    let large = HugeVec::from(items.clone());
    assert!(large.is_mapped());
    assert_eq!(large, items);
}

/// `AnonHugePages` of the mapping that holds `addr`, from `/proc/self/smaps`, in kB.
#[cfg(target_os = "linux")]
fn huge_kib_at(addr: usize) -> usize {
    let smaps = std::fs::read_to_string("/proc/self/smaps").unwrap_or_default();
    let mut inside = false;
    for line in smaps.lines() {
        let range = line
            .split_whitespace()
            .next()
            .and_then(|r| r.split_once('-'));
        if let Some((lo, hi)) = range
            && let (Ok(lo), Ok(hi)) = (usize::from_str_radix(lo, 16), usize::from_str_radix(hi, 16))
        {
            inside = (lo..hi).contains(&addr);
        } else if inside && let Some(kib) = line.strip_prefix("AnonHugePages:") {
            return kib
                .trim()
                .trim_end_matches("kB")
                .trim()
                .parse()
                .unwrap_or(0);
        }
    }
    0
}

/// The pages of a large array are in fact huge where the kernel offers them on request
/// (`madvise` or `always` mode): its mapping's `AnonHugePages` in `/proc/self/smaps`.
#[cfg(target_os = "linux")]
#[test]
fn a_large_array_is_backed_by_huge_pages_when_the_kernel_offers_them() {
    let mode = std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/enabled");
    let Ok(mode) = mode else { return };
    if mode.contains("[never]") {
        return;
    }
    let n = count_for(8 * HUGE_PAGE);
    let mut v = HugeVec::with_capacity(n);
    for i in 0..n {
        v.push(item(i));
    }
    assert_eq!(v[n - 1], item(n - 1));
    // The kernel may lack free huge pages at a given moment: at least half of them.
    let kib = huge_kib_at(v.as_ptr() as usize);
    assert!(kib >= 4 * HUGE_PAGE / 1024, "AnonHugePages {kib} kB");
    // A Vec of the same size is not in `madvise` mode (glibc's malloc does not advise).
    if mode.contains("[madvise]") {
        let heap = HugeVec::from_slice(&v, Backing::Heap);
        assert_eq!(heap, v);
        assert_eq!(huge_kib_at(heap.as_ptr() as usize), 0);
    }
}

#[test]
fn a_huge_slice_keeps_the_vecs_elements_and_memory() {
    let large = count_for(3 * MIN_MAPPED_BYTES);
    for backing in [Backing::Auto, Backing::Heap, Backing::Mapped] {
        for n in [0, 1, 1000, large] {
            let items: Vec<Item> = (0..n).map(item).collect();
            let v = HugeVec::from_slice(&items, backing);
            let (ptr, mapped, reserved) = (v.as_ptr(), v.is_mapped(), v.reserved_bytes());
            let s = HugeSlice::from(v);
            // Not copied: the same memory, the same backing.
            assert_eq!((s.as_ptr(), s.is_mapped()), (ptr, mapped));
            assert_eq!(s.reserved_bytes(), reserved);
            assert_eq!(s, items);
            assert_eq!(s.len(), n);
            assert_eq!(format!("{s:?}"), format!("{items:?}"));
            let copy = s.clone();
            assert_eq!(copy, s);
            assert_eq!(
                copy.is_mapped(),
                mapped || backing == Backing::Auto && n >= large
            );
            let mut changed = s.clone();
            let mut want = items.clone();
            if n > 0 {
                changed.modify(|x| x[n - 1].a[0] = 12345);
                want[n - 1].a[0] = 12345;
                assert_ne!(changed, s);
            }
            assert_eq!(changed, want);
            assert_eq!(changed.is_mapped(), copy.is_mapped());
        }
    }
    let empty = HugeSlice::<Item>::default();
    assert!(empty.is_empty() && !empty.is_mapped());
    assert_eq!(empty.reserved_bytes(), 0);
    assert_eq!(empty.clone(), empty);
    let mut grown = empty.clone();
    grown.modify(|x| assert!(x.is_empty()));
    assert_eq!(grown, Vec::new());
    let from_vec = HugeSlice::from((0..large).map(item).collect::<Vec<_>>());
    assert!(from_vec.is_mapped());
    assert_eq!(from_vec[large - 1], item(large - 1));
}
