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
