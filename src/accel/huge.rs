//! [`HugeVec`]: a growable array for the BVH's large arrays (the wide nodes and leaf
//! groups, the binary tree's nodes and primitive order, and the build's and the
//! collapse's working arrays), kept in memory that the OS may back with transparent
//! huge pages.
//!
//! Why: an incoherent ray's node and leaf loads land all over a BVH of tens of
//! megabytes, and with 4 KiB pages most of them also miss the TLB. Linux backs
//! anonymous memory with 2 MiB pages only where asked (`madvise` mode, the common
//! default) and only for 2 MiB-aligned extents, which `malloc` neither asks for nor
//! aligns. So an array of at least [`MIN_MAPPED_BYTES`] gets an anonymous mapping of its
//! own (`memmap2`'s safe API: glint forbids any other), starting on a 2 MiB boundary
//! and advised `MADV_HUGEPAGE` on Linux (torus 1M, glibc's `hugetlb` tunable, which
//! does the same for every large `malloc`: incoherent rays -10 to -14%). Elsewhere, or
//! when the advice or the mapping fails, it is a plain mapping, or a plain `Vec`; the
//! contents and every operation are the same either way. Smaller arrays stay in a
//! `Vec`: below a huge page nothing can pay, and a mapping each would cost a system
//! call and a kernel memory area per small instanced BVH.

use std::fmt;
use std::marker::PhantomData;
use std::ops::{Deref, DerefMut};

use bytemuck::Pod;
use memmap2::{MmapMut, MmapOptions};
use yoke::Yoke;

/// The extent of a transparent huge page on x86-64 and aarch64 with 4 KiB base pages.
pub const HUGE_PAGE: usize = 2 << 20;

/// Capacity in bytes from which a `HugeVec` takes a mapping of its own (with
/// [`Backing::Auto`]): one huge page, below which none can be whole.
pub const MIN_MAPPED_BYTES: usize = HUGE_PAGE;

/// Where a [`HugeVec`] keeps its elements.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backing {
    /// A mapping from [`MIN_MAPPED_BYTES`] on, a `Vec` below.
    Auto,
    /// Always a `Vec` (what any failure falls back to).
    Heap,
    /// Always a mapping, whatever the size (tests of the mapped path on small data).
    Mapped,
}

/// A growable array of plain data, in huge-page-advised memory when it is large (see
/// the module's documentation); reads and writes go through `Deref<Target = [T]>`.
pub struct HugeVec<T: Pod> {
    store: Store<T>,
    backing: Backing,
}

enum Store<T> {
    Heap(Vec<T>),
    Mapped(Mapped<T>),
}

/// Elements `0..len` of `T` at byte `start` of `map` (a 2 MiB boundary), room for `cap`.
struct Mapped<T> {
    map: MmapMut,
    start: usize,
    len: usize,
    cap: usize,
    _elements: PhantomData<T>,
}

impl<T: Pod> Mapped<T> {
    /// A mapping with room for `cap` elements (at least one), or `None` when the OS
    /// refuses one (or `T` takes no memory).
    fn new(cap: usize) -> Option<Mapped<T>> {
        let bytes = cap.max(1).checked_mul(size_of::<T>())?;
        if bytes == 0 {
            return None;
        }
        // Whole huge pages, and one more to slide the start to a 2 MiB boundary: the
        // slack is address space, never touched, so it takes no memory.
        let reserve = bytes
            .checked_next_multiple_of(HUGE_PAGE)?
            .checked_add(HUGE_PAGE)?;
        let map = MmapOptions::new().len(reserve).map_anon().ok()?;
        let base = map.as_ptr() as usize;
        let start = base.next_multiple_of(HUGE_PAGE) - base;
        // Advice only: on a kernel without transparent huge pages it fails, and the
        // mapping is a plain one.
        #[cfg(target_os = "linux")]
        let _ = map.advise_range(memmap2::Advice::HugePage, start, reserve - start);
        Some(Mapped {
            map,
            start,
            len: 0,
            cap: (reserve - start) / size_of::<T>(),
            _elements: PhantomData,
        })
    }

    #[inline(always)]
    fn as_slice(&self) -> &[T] {
        let end = self.start + self.len * size_of::<T>();
        bytemuck::cast_slice(&self.map[self.start..end])
    }

    #[inline(always)]
    fn as_mut_slice(&mut self) -> &mut [T] {
        let end = self.start + self.len * size_of::<T>();
        bytemuck::cast_slice_mut(&mut self.map[self.start..end])
    }
}

impl<T: Pod> HugeVec<T> {
    /// An empty array (no memory until something is pushed), backed as [`Backing::Auto`].
    pub fn new() -> HugeVec<T> {
        HugeVec {
            store: Store::Heap(Vec::new()),
            backing: Backing::Auto,
        }
    }

    /// Room for `cap` elements, in a mapping from [`MIN_MAPPED_BYTES`] on.
    pub fn with_capacity(cap: usize) -> HugeVec<T> {
        HugeVec::with_backing(cap, Backing::Auto)
    }

    /// Room for `cap` elements, kept as `backing` says (a `Vec` if a mapping fails).
    pub fn with_backing(cap: usize, backing: Backing) -> HugeVec<T> {
        let store = match Self::wants_mapping(cap, backing).then(|| Mapped::new(cap)) {
            Some(Some(mapped)) => Store::Mapped(mapped),
            _ => Store::Heap(Vec::with_capacity(cap)),
        };
        HugeVec { store, backing }
    }

    /// `len` zeroed elements, kept as `backing` says: a fresh mapping is zeroed already,
    /// and a `Vec` comes zeroed from the allocator, so neither takes a pass writing
    /// zeros (the pages are zeroed as they are first touched).
    pub fn zeroed(len: usize, backing: Backing) -> HugeVec<T> {
        let mapped = Self::wants_mapping(len, backing).then(|| Mapped::new(len));
        let store = match mapped {
            Some(Some(mut m)) => {
                m.len = len;
                Store::Mapped(m)
            }
            _ => Store::Heap(bytemuck::zeroed_vec(len)),
        };
        HugeVec { store, backing }
    }

    /// The elements of `items`, kept as `backing` says.
    pub fn from_slice(items: &[T], backing: Backing) -> HugeVec<T> {
        let mut v = HugeVec::with_backing(items.len(), backing);
        v.extend_from_slice(items);
        v
    }

    fn wants_mapping(cap: usize, backing: Backing) -> bool {
        match backing {
            Backing::Auto => cap.saturating_mul(size_of::<T>()) >= MIN_MAPPED_BYTES,
            Backing::Heap => false,
            Backing::Mapped => true,
        }
    }

    /// True when the elements sit in a mapping of their own (see [`Backing`]).
    pub fn is_mapped(&self) -> bool {
        matches!(self.store, Store::Mapped(_))
    }

    /// Elements that fit without moving.
    pub fn capacity(&self) -> usize {
        match &self.store {
            Store::Heap(v) => v.capacity(),
            Store::Mapped(m) => m.cap,
        }
    }

    /// Bytes of address space reserved: the `Vec`'s capacity, or the whole mapping
    /// (whole huge pages and the alignment slack, of which only the pages touched take
    /// memory: the elements, rounded up to a huge page where the OS gave them).
    pub fn reserved_bytes(&self) -> usize {
        match &self.store {
            Store::Heap(v) => v.capacity() * size_of::<T>(),
            Store::Mapped(m) => m.map.len(),
        }
    }

    /// The elements.
    #[inline(always)]
    pub fn as_slice(&self) -> &[T] {
        match &self.store {
            Store::Heap(v) => v,
            Store::Mapped(m) => m.as_slice(),
        }
    }

    /// The elements, to write.
    #[inline(always)]
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        match &mut self.store {
            Store::Heap(v) => v,
            Store::Mapped(m) => m.as_mut_slice(),
        }
    }

    /// Makes room for `extra` more elements: like a `Vec`, at least doubling, and moving
    /// into a mapping once the array reaches [`MIN_MAPPED_BYTES`] (with `Auto`).
    pub fn reserve(&mut self, extra: usize) {
        let len = self.len();
        let need = len.checked_add(extra).expect("HugeVec capacity overflow");
        if need <= self.capacity() {
            return;
        }
        let cap = need.max(2 * self.capacity());
        match &mut self.store {
            Store::Heap(v) if !Self::wants_mapping(cap, self.backing) => v.reserve(extra),
            _ => {
                let mut bigger = HugeVec::with_backing(cap, self.backing);
                bigger.extend_from_slice(self.as_slice());
                self.store = bigger.store;
            }
        }
    }

    /// Appends `value`.
    #[inline]
    pub fn push(&mut self, value: T) {
        match &mut self.store {
            Store::Heap(v) if v.len() < v.capacity() => v.push(value),
            Store::Mapped(m) if m.len < m.cap => {
                m.len += 1;
                let last = m.len - 1;
                m.as_mut_slice()[last] = value;
            }
            _ => {
                self.reserve(1);
                self.push(value);
            }
        }
    }

    /// Appends the elements of `items`.
    pub fn extend_from_slice(&mut self, items: &[T]) {
        self.reserve(items.len());
        match &mut self.store {
            Store::Heap(v) => v.extend_from_slice(items),
            Store::Mapped(m) => {
                let start = m.len;
                m.len += items.len();
                m.as_mut_slice()[start..].copy_from_slice(items);
            }
        }
    }

    /// Keeps the first `len` elements (all of them when there are fewer).
    pub fn truncate(&mut self, len: usize) {
        match &mut self.store {
            Store::Heap(v) => v.truncate(len),
            Store::Mapped(m) => m.len = m.len.min(len),
        }
    }

    /// Gives back unused capacity of a `Vec`; a mapping keeps its address space, whose
    /// untouched pages take no memory.
    pub fn shrink_to_fit(&mut self) {
        if let Store::Heap(v) = &mut self.store {
            v.shrink_to_fit();
        }
    }
}

impl<T: Pod> Default for HugeVec<T> {
    fn default() -> HugeVec<T> {
        HugeVec::new()
    }
}

impl<T: Pod> DerefMut for HugeVec<T> {
    #[inline(always)]
    fn deref_mut(&mut self) -> &mut [T] {
        self.as_mut_slice()
    }
}

/// A copy kept as the original's backing asks, sized to its length.
impl<T: Pod> Clone for HugeVec<T> {
    fn clone(&self) -> HugeVec<T> {
        HugeVec::from_slice(self, self.backing)
    }
}

impl<T: Pod> From<Vec<T>> for HugeVec<T> {
    /// The same elements, moved into a mapping when large.
    fn from(v: Vec<T>) -> HugeVec<T> {
        if HugeVec::<T>::wants_mapping(v.len(), Backing::Auto) {
            HugeVec::from_slice(&v, Backing::Auto)
        } else {
            HugeVec {
                store: Store::Heap(v),
                backing: Backing::Auto,
            }
        }
    }
}

/// A [`HugeVec`] done growing: the same elements in the same memory, read at a `Vec`'s
/// cost. A `HugeVec`'s every read looks at its backing (a branch and a cast: +15%
/// instructions per ray, torus 100k, when the BVH's arrays were `HugeVec`s); here the
/// slice is kept beside the storage it borrows from (`yoke`), so a read loads it and
/// nothing else.
pub struct HugeSlice<T: Pod> {
    items: Yoke<&'static [T], Option<Box<HugeVec<T>>>>,
}

impl<T: Pod> HugeSlice<T> {
    /// The storage, or `None` for an empty slice made by `default`.
    fn storage(&self) -> Option<&HugeVec<T>> {
        self.items.backing_cart().as_deref()
    }

    /// True when the elements sit in a mapping of their own (see [`Backing`]).
    pub fn is_mapped(&self) -> bool {
        self.storage().is_some_and(HugeVec::is_mapped)
    }

    /// Bytes of address space reserved ([`HugeVec::reserved_bytes`]).
    pub fn reserved_bytes(&self) -> usize {
        self.storage().map_or(0, HugeVec::reserved_bytes)
    }

    /// The elements.
    #[inline(always)]
    pub fn as_slice(&self) -> &[T] {
        self.items.get()
    }

    /// Lets `edit` change the elements in place (the slice is let go of and taken
    /// again around it): for tests that break a tree on purpose.
    pub fn modify(&mut self, edit: impl FnOnce(&mut [T])) {
        let items = std::mem::replace(&mut self.items, Yoke::new_owned(&[]));
        let mut storage = items.into_backing_cart().map_or_else(HugeVec::new, |b| *b);
        edit(&mut storage);
        *self = HugeSlice::from(storage);
    }
}

impl<T: Pod> From<HugeVec<T>> for HugeSlice<T> {
    /// The elements of `storage`, not copied.
    fn from(storage: HugeVec<T>) -> HugeSlice<T> {
        let items = Yoke::attach_to_cart(Box::new(storage), |s: &HugeVec<T>| s.as_slice());
        HugeSlice {
            items: items.wrap_cart_in_option(),
        }
    }
}

impl<T: Pod> From<Vec<T>> for HugeSlice<T> {
    /// The same elements, moved into a mapping when large.
    fn from(v: Vec<T>) -> HugeSlice<T> {
        HugeSlice::from(HugeVec::from(v))
    }
}

impl<T: Pod> Default for HugeSlice<T> {
    /// Empty, with no storage at all.
    fn default() -> HugeSlice<T> {
        HugeSlice {
            items: Yoke::new_owned(&[]),
        }
    }
}

/// A copy kept as the original's backing asks.
impl<T: Pod> Clone for HugeSlice<T> {
    fn clone(&self) -> HugeSlice<T> {
        match self.storage() {
            Some(s) => HugeSlice::from(s.clone()),
            None => HugeSlice::default(),
        }
    }
}

/// What both array types forward to their slice: `Deref`, `Debug`, equality (with each
/// other's kind and with a `Vec`) and iteration by reference.
macro_rules! slice_views {
    ($($ty:ident),*) => {$(
        impl<T: Pod> Deref for $ty<T> {
            type Target = [T];

            #[inline(always)]
            fn deref(&self) -> &[T] {
                self.as_slice()
            }
        }

        impl<T: Pod + fmt::Debug> fmt::Debug for $ty<T> {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                self.as_slice().fmt(f)
            }
        }

        impl<T: Pod + PartialEq> PartialEq for $ty<T> {
            fn eq(&self, other: &$ty<T>) -> bool {
                self.as_slice() == other.as_slice()
            }
        }

        impl<T: Pod + PartialEq> PartialEq<Vec<T>> for $ty<T> {
            fn eq(&self, other: &Vec<T>) -> bool {
                self.as_slice() == other.as_slice()
            }
        }

        impl<'a, T: Pod> IntoIterator for &'a $ty<T> {
            type Item = &'a T;
            type IntoIter = std::slice::Iter<'a, T>;

            fn into_iter(self) -> Self::IntoIter {
                self.as_slice().iter()
            }
        }
    )*};
}

slice_views!(HugeVec, HugeSlice);

#[cfg(test)]
#[path = "huge_tests.rs"]
mod tests;
