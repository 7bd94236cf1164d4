//! Arrays of plain data the kernel may back with transparent huge pages: the BVH's nodes and
//! leaves. A ray through the 1M-triangle terrain reads a few nodes and leaves scattered over
//! some 53 MB; in 4 KiB pages most of those reads also miss the TLB. Embree asks for huge
//! pages for its own BVH (its terrain held 58 MB of them), so the comparison is made on equal
//! terms (on the terrain with `bench-accel`, BVH/Embree went from 0.58–0.65 to 0.69–0.72). The memory is an
//! anonymous mapping (memmap2) advised with `MADV_HUGEPAGE`, which counts whether the system's
//! setting is `always` or `madvise`; it is read and written as a typed slice over the
//! mapping's bytes (bytemuck), so no `unsafe` is needed here.

use std::ops::Deref;

use bytemuck::Pod;
use memmap2::MmapMut;

/// Arrays smaller than one huge page stay on the heap.
const HUGE_PAGE: usize = 2 << 20;

/// An immutable array of `T`, in huge pages when it is large enough and the system allows.
pub(super) struct HugePageArray<T: Pod> {
    storage: Storage<T>,
}

enum Storage<T> {
    Mapped(MmapMut),
    Heap(Vec<T>),
}

impl<T: Pod> HugePageArray<T> {
    /// The array holding `data`.
    pub fn new(data: Vec<T>) -> HugePageArray<T> {
        HugePageArray::filled(data.len(), |array| array.copy_from_slice(&data))
    }

    /// An array of `len` elements, zeroed, then written by `fill` (in place: a large array is
    /// not built elsewhere and copied).
    pub fn filled(len: usize, fill: impl FnOnce(&mut [T])) -> HugePageArray<T> {
        let bytes = len * size_of::<T>();
        let mut storage = match bytes >= HUGE_PAGE {
            true => match mapped(bytes) {
                Some(map) => Storage::Mapped(map),
                None => Storage::Heap(vec![T::zeroed(); len]),
            },
            false => Storage::Heap(vec![T::zeroed(); len]),
        };
        fill(match &mut storage {
            Storage::Mapped(map) => bytemuck::cast_slice_mut(map),
            Storage::Heap(v) => v,
        });
        HugePageArray { storage }
    }
}

/// A zeroed mapping of `bytes`, advised for huge pages before it is written (the pages are
/// chosen when first touched); None when the system gives no anonymous mapping.
fn mapped(bytes: usize) -> Option<MmapMut> {
    let map = MmapMut::map_anon(bytes).ok()?;
    // Only advice: where the kernel has no transparent huge pages, 4 KiB pages serve.
    #[cfg(target_os = "linux")]
    let _ = map.advise(memmap2::Advice::HugePage);
    Some(map)
}

impl<T: Pod> Deref for HugePageArray<T> {
    type Target = [T];

    fn deref(&self) -> &[T] {
        match &self.storage {
            // A mapping starts on a page boundary, aligned for any `T` of ours.
            Storage::Mapped(map) => bytemuck::cast_slice(map),
            Storage::Heap(v) => v,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_filled_in_place_read_back_as_written() {
        let array = HugePageArray::<u64>::filled(1 << 20, |a| {
            for (i, x) in a.iter_mut().enumerate() {
                *x = i as u64 * 3;
            }
        });
        assert!(matches!(array.storage, Storage::Mapped(_)));
        assert!(array.iter().enumerate().all(|(i, &x)| x == i as u64 * 3));
        let small = HugePageArray::<u64>::filled(5, |a| a[4] = 9);
        assert_eq!(&small[..], &[0, 0, 0, 0, 9]);
    }

    #[test]
    fn small_and_large_arrays_read_back_as_written() {
        for n in [0usize, 1, 1000, 3 << 20] {
            let data: Vec<[u32; 4]> = (0..n as u32).map(|i| [i, !i, i ^ 7, 3]).collect();
            let array = HugePageArray::new(data.clone());
            assert_eq!(&array[..], &data[..], "{n} elements");
            assert_eq!(
                matches!(array.storage, Storage::Mapped(_)),
                n * 16 >= HUGE_PAGE,
                "{n} elements mapped only when large"
            );
        }
    }
}
