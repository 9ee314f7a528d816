//! Order-preserving parallel map over the available cores, for CPU work at
//! load time (image decoding, static BVH builds). The lowest layer: it
//! imports nothing of the crate.

use std::sync::atomic::{AtomicUsize, Ordering};

use anyhow::{bail, Result};

/// `f(i)` for every `i` in `0..n` on up to all available cores, returned in
/// index order. Work is handed out one item at a time in `order` (every
/// index once; empty: `0..n`), so listing the costliest items first keeps
/// one big item from finishing alone at the end. A panic in `f` is an error.
pub fn map<R: Send>(n: usize, order: &[usize], f: impl Fn(usize) -> R + Sync) -> Result<Vec<R>> {
    assert!(order.is_empty() || order.len() == n, "par::map: order lists {} of {n} items", order.len());
    let next = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism().map_or(1, |c| c.get()).min(n).max(1);
    let joined: Vec<_> = std::thread::scope(|s| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                s.spawn(|| {
                    let mut out = Vec::new();
                    loop {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        if k >= n {
                            break out;
                        }
                        let i = order.get(k).copied().unwrap_or(k);
                        out.push((i, f(i)));
                    }
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join()).collect()
    });
    let mut slots: Vec<Option<R>> = (0..n).map(|_| None).collect();
    for part in joined {
        let Ok(part) = part else { bail!("a worker thread panicked") };
        for (i, r) in part {
            slots[i] = Some(r);
        }
    }
    slots
        .into_iter()
        .enumerate()
        .map(|(i, r)| r.ok_or_else(|| anyhow::anyhow!("item {i} was never computed")))
        .collect()
}

/// Fills `out` on every core, `chunk` items at a time: `f(first, part)` writes `part`, which is
/// `out[first .. first + part.len()]`. A panic in `f` is an error.
pub fn fill<T: Send>(out: &mut [T], chunk: usize, f: impl Fn(usize, &mut [T]) + Sync) -> Result<()> {
    let chunk = chunk.max(1);
    let parts: Vec<std::sync::Mutex<Option<&mut [T]>>> =
        out.chunks_mut(chunk).map(|c| std::sync::Mutex::new(Some(c))).collect();
    map(parts.len(), &[], |k| {
        let part = parts[k].lock().map(|mut p| p.take()).ok().flatten();
        if let Some(part) = part {
            f(k * chunk, part);
        }
    })?;
    Ok(())
}

/// `out[j] = f(j)` for every `j`: on every core, `chunk` items at a time, when `out` holds at least two
/// chunks; else on this thread (starting threads would cost more than the work). A panic in `f` is an
/// error.
pub fn fill_each<T: Send>(out: &mut [T], chunk: usize, f: impl Fn(usize) -> T + Sync) -> Result<()> {
    let serial =
        |first: usize, part: &mut [T]| part.iter_mut().enumerate().for_each(|(j, o)| *o = f(first + j));
    if out.len() < 2 * chunk.max(1) {
        serial(0, out);
        Ok(())
    } else {
        fill(out, chunk, serial)
    }
}

/// `(0..n).map(f).collect()`, on every core in chunks of `chunk` when `n` is at least two chunks. The
/// vector is written once (no initialising pass before the parallel one). A panic in `f` is an error.
pub fn collect_each<T: Send>(n: usize, chunk: usize, f: impl Fn(usize) -> T + Sync) -> Result<Vec<T>> {
    let mut out: Vec<T> = Vec::with_capacity(n);
    fill_each(&mut out.spare_capacity_mut()[..n], chunk, |i| std::mem::MaybeUninit::new(f(i)))?;
    // SAFETY: `fill_each` returned Ok, so every one of the first n slots was written.
    unsafe { out.set_len(n) };
    Ok(out)
}

/// Appends `parts` to `out`, each item mapped by `f(part index, item)`, the parts copied on every core
/// (a large tree's subtrees linked in after its top). A panic in `f` is an error; `out` is then unchanged.
pub fn extend_parts<T: Sync, U: Send>(
    out: &mut Vec<U>,
    parts: &[&[T]],
    f: impl Fn(usize, &T) -> U + Sync,
) -> Result<()> {
    let total: usize = parts.iter().map(|p| p.len()).sum();
    out.reserve(total);
    let mut rest = &mut out.spare_capacity_mut()[..total];
    let mut slots = Vec::with_capacity(parts.len());
    for p in parts {
        let (mine, tail) = std::mem::take(&mut rest).split_at_mut(p.len());
        slots.push(std::sync::Mutex::new(Some(mine)));
        rest = tail;
    }
    map(parts.len(), &[], |k| {
        if let Some(dst) = slots[k].lock().map(|mut s| s.take()).ok().flatten() {
            for (d, item) in dst.iter_mut().zip(parts[k]) {
                d.write(f(k, item));
            }
        }
    })?;
    // SAFETY: `map` returned Ok, so every part's slots (the first `total` spare ones) were written.
    unsafe { out.set_len(out.len() + total) };
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn results_come_back_in_index_order_whatever_the_hand_out_order() {
        let order: Vec<usize> = (0..100).rev().collect();
        let out = super::map(100, &order, |i| i * i).unwrap();
        assert_eq!(out, (0..100).map(|i| i * i).collect::<Vec<_>>());
        assert_eq!(super::map(0, &[], |i| i).unwrap(), Vec::<usize>::new());
    }

    #[test]
    fn fill_each_writes_each_item_from_its_index_serial_or_not() {
        for (n, chunk) in [(0, 4), (7, 4), (8, 4), (1000, 64), (5, 0)] {
            let mut out = vec![usize::MAX; n];
            super::fill_each(&mut out, chunk, |j| j * 7 + 1).unwrap();
            assert_eq!(out, (0..n).map(|j| j * 7 + 1).collect::<Vec<_>>(), "{n} items, chunks of {chunk}");
        }
        let mut out = vec![0u8; 100];
        assert!(super::fill_each(&mut out, 10, |j| if j == 57 { panic!("item 57") } else { 1 }).is_err());
    }

    #[test]
    fn collect_each_is_the_serial_collect() {
        for (n, chunk) in [(0, 4), (7, 4), (8, 4), (1000, 64)] {
            let v = super::collect_each(n, chunk, |i| vec![i; i % 3]).unwrap();
            assert_eq!(v, (0..n).map(|i| vec![i; i % 3]).collect::<Vec<_>>(), "{n} items, chunks of {chunk}");
        }
        assert!(super::collect_each(100, 10, |i| if i == 57 { panic!("item 57") } else { i }).is_err());
    }

    #[test]
    fn extend_parts_appends_each_part_in_order() {
        let parts: Vec<Vec<u32>> = (0..40).map(|k| (0..k * 3).collect()).collect();
        let refs: Vec<&[u32]> = parts.iter().map(|p| &p[..]).collect();
        let mut out = vec![7u64, 8];
        super::extend_parts(&mut out, &refs, |k, &x| (k as u64) << 32 | x as u64).unwrap();
        let want: Vec<u64> = [7, 8]
            .into_iter()
            .chain(
                parts
                    .iter()
                    .enumerate()
                    .flat_map(|(k, p)| p.iter().map(move |&x| (k as u64) << 32 | x as u64)),
            )
            .collect();
        assert_eq!(out, want);
        let mut out = vec![1u8];
        assert!(
            super::extend_parts(&mut out, &refs, |k, _| if k == 5 { panic!("part 5") } else { 0 }).is_err()
        );
        assert_eq!(out, vec![1], "unchanged after a panic");
    }

    #[test]
    fn fill_writes_every_item_once_at_its_index() {
        for (n, chunk) in [(0, 4), (1, 4), (10, 3), (1000, 64), (7, 0)] {
            let mut out = vec![usize::MAX; n];
            super::fill(&mut out, chunk, |first, part| {
                for (j, v) in part.iter_mut().enumerate() {
                    assert_eq!(*v, usize::MAX, "written twice");
                    *v = (first + j) * 3;
                }
            })
            .unwrap();
            assert_eq!(out, (0..n).map(|i| i * 3).collect::<Vec<_>>(), "{n} items in chunks of {chunk}");
        }
        assert!(super::fill(&mut [0u8; 10], 2, |first, _| assert!(first != 4)).is_err());
    }

    #[test]
    fn a_panicking_item_is_an_error() {
        let r = super::map(8, &[], |i| if i == 5 { panic!("item 5") } else { i });
        assert!(r.is_err());
    }
}
