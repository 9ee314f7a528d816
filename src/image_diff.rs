//! Image error metrics for tests and benchmarks.

/// PSNR in dB between two equally sized 8-bit RGB(A) buffers, over the pixels
/// where `mask` (if given) is true. Infinite for identical images.
pub fn psnr_rgb8(a: &[u8], b: &[u8], channels: usize, mask: Option<&[bool]>) -> f64 {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let mut sum = 0.0f64;
    let mut n = 0usize;
    for (i, (pa, pb)) in a.chunks_exact(channels).zip(b.chunks_exact(channels)).enumerate() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        for c in 0..channels.min(3) {
            let d = pa[c] as f64 - pb[c] as f64;
            sum += d * d;
            n += 1;
        }
    }
    if n == 0 || sum == 0.0 {
        return f64::INFINITY;
    }
    let mse = sum / n as f64;
    10.0 * (255.0f64 * 255.0 / mse).log10()
}

/// Largest per-channel difference and the fraction of pixels that differ by
/// more than `threshold` in any channel.
pub fn diff_stats(a: &[u8], b: &[u8], channels: usize, threshold: u8) -> (u8, f64) {
    let mut max = 0u8;
    let mut differing = 0usize;
    let mut total = 0usize;
    for (pa, pb) in a.chunks_exact(channels).zip(b.chunks_exact(channels)) {
        let d = (0..channels.min(3)).map(|c| pa[c].abs_diff(pb[c])).max().unwrap_or(0);
        max = max.max(d);
        differing += (d > threshold) as usize;
        total += 1;
    }
    (max, differing as f64 / total.max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psnr_identical_is_infinite_and_known_error_matches() {
        let a = vec![100u8; 300];
        assert!(psnr_rgb8(&a, &a, 3, None).is_infinite());
        let mut b = a.clone();
        for v in b.iter_mut() {
            *v = 110;
        }
        // MSE 100 -> 10 log10(65025 / 100) = 28.13 dB.
        assert!((psnr_rgb8(&a, &b, 3, None) - 28.1308).abs() < 1e-3);
        assert_eq!(diff_stats(&a, &b, 3, 5), (10, 1.0));
    }
}
