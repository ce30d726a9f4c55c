//! A stable counting sort by small integer keys, cache-friendly at millions
//! of keys: it orders the half-edges of the mesh (`edges.rs`) and the
//! triangles by their lowest point (`stiffness.rs`), docs/methods.md §2.3.

/// Stable counting sort of the items that `gen` yields (called twice, and
/// yielding the same items each time) by `key(item) < nkeys`: the sorted
/// items and `ptr` (nkeys + 1 entries; key k's items are `ptr[k]..ptr[k + 1]`).
///
/// One counting pass over millions of keys writes at random and misses the
/// cache on nearly every item; so a first pass buckets by the high bits of
/// the key (about 2048 buckets: a few streams of writes) and a second sorts
/// each small bucket by the whole key, in cache.
pub(crate) fn bucket_sort<T, I>(
    gen: impl Fn() -> I,
    key: impl Fn(&T) -> usize,
    nkeys: usize,
) -> (Vec<T>, Vec<usize>)
where
    T: Copy + Default,
    I: Iterator<Item = T>,
{
    let bits = usize::BITS - nkeys.leading_zeros();
    let shift = bits.saturating_sub(11);
    let nbk = (nkeys >> shift) + 1;
    let mut bptr = vec![0usize; nbk + 1];
    for x in gen() {
        bptr[(key(&x) >> shift) + 1] += 1;
    }
    for b in 0..nbk {
        bptr[b + 1] += bptr[b];
    }
    let mut items = vec![T::default(); bptr[nbk]];
    {
        let mut fill = bptr[..nbk].to_vec();
        for x in gen() {
            let b = key(&x) >> shift;
            items[fill[b]] = x;
            fill[b] += 1;
        }
    }
    let mut ptr = vec![0usize; nkeys + 1];
    let mut scratch: Vec<T> = vec![];
    let mut cnt: Vec<usize> = vec![];
    for b in 0..nbk {
        let slice = &mut items[bptr[b]..bptr[b + 1]];
        let base = b << shift;
        let width = (1usize << shift).min(nkeys.saturating_sub(base));
        cnt.clear();
        cnt.resize(width + 1, 0);
        for x in slice.iter() {
            cnt[key(x) - base + 1] += 1;
        }
        for i in 0..width {
            ptr[base + i + 1] = cnt[i + 1];
            cnt[i + 1] += cnt[i];
        }
        scratch.clear();
        scratch.resize(slice.len(), T::default());
        for x in slice.iter() {
            let i = key(x) - base;
            scratch[cnt[i]] = *x;
            cnt[i] += 1;
        }
        slice.copy_from_slice(&scratch);
    }
    for k in 0..nkeys {
        ptr[k + 1] += ptr[k];
    }
    (items, ptr)
}

#[cfg(test)]
mod tests {
    #[test]
    fn bucket_sort_is_a_stable_counting_sort() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for nkeys in [0usize, 1, 5, 2047, 2048, 2049, 5000, 100_000] {
            let items: Vec<(usize, usize)> = (0..3 * nkeys + 7)
                .filter(|_| nkeys > 0)
                .map(|i| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    ((s % nkeys.max(1) as u64) as usize, i)
                })
                .collect();
            let (sorted, ptr) = super::bucket_sort(|| items.iter().copied(), |x| x.0, nkeys);
            let mut expect = items.clone();
            expect.sort_by_key(|x| x.0);
            assert_eq!(sorted, expect);
            assert_eq!(ptr.len(), nkeys + 1);
            for k in 0..nkeys {
                assert!(sorted[ptr[k]..ptr[k + 1]].iter().all(|x| x.0 == k));
            }
        }
    }
}
