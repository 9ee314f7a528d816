//! What every on-disk cache shares (the PRT transfer's, the compute BVH's): the directory by the
//! platform convention, a fast content hash for keys and checksums, and a file format that is
//! checked before it is trusted. The lowest layer beside `par`: it imports nothing of the crate.
//!
//! A file is `magic (8) | key (8) | payload length (8) | payload | hash of the payload (8)`, written
//! to a temporary name and renamed (atomic on one file system), so a reader sees a whole file or
//! none; a short, foreign, stale or corrupt file is an error for the caller to recompute from.

use std::path::{Path, PathBuf};

use std::io::{Read as _, Write as _};

use anyhow::{ensure, Context as _, Result};

/// A cache directory by the platform convention: `$override_env`, else
/// `$XDG_CACHE_HOME/hybrid-rt/<sub>`, else `~/.cache/hybrid-rt/<sub>`.
pub fn user_cache_dir(override_env: &str, sub: &str) -> Option<PathBuf> {
    let env = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    env(override_env)
        .or_else(|| env("XDG_CACHE_HOME").map(|d| d.join("hybrid-rt").join(sub)))
        .or_else(|| env("HOME").map(|h| h.join(".cache/hybrid-rt").join(sub)))
}

/// FNV-1a's multiply-xor over 8-byte words in four interleaved lanes (32-byte blocks; the tail
/// zero-padded, the length mixed in at the end): byte-wise FNV took longer to hash a 4 M triangle tree
/// than to build it, one lane of words a third of reading it back. Streaming: hashing parts one after
/// another equals hashing them joined, so a caller hashing several fields puts their lengths in. A
/// checksum and a cache key, not a cryptographic hash.
pub struct Hash64 {
    lanes: [u64; 4],
    tail: [u8; 32],
    pending: usize,
    len: u64,
}

impl Default for Hash64 {
    fn default() -> Self {
        let seed = 0xcbf2_9ce4_8422_2325u64;
        Hash64 { lanes: [seed, seed ^ 1, seed ^ 2, seed ^ 3], tail: [0; 32], pending: 0, len: 0 }
    }
}

#[inline(always)]
fn mix(h: u64, w: u64) -> u64 {
    // The xor-shifts spread each word's and the state's high bits into the low ones the multiply uses.
    ((h ^ w ^ (w >> 29)).wrapping_mul(0x100_0000_01b3)) ^ (h >> 31)
}

impl Hash64 {
    #[inline(always)]
    fn block(&mut self, b: &[u8]) {
        for (lane, w) in self.lanes.iter_mut().zip(b.chunks_exact(8)) {
            *lane = mix(*lane, u64::from_le_bytes(w.try_into().unwrap_or_default()));
        }
    }

    pub fn bytes(&mut self, mut b: &[u8]) {
        self.len += b.len() as u64;
        if self.pending > 0 {
            let take = b.len().min(32 - self.pending);
            self.tail[self.pending..self.pending + take].copy_from_slice(&b[..take]);
            self.pending += take;
            b = &b[take..];
            if self.pending < 32 {
                return;
            }
            let tail = self.tail;
            self.block(&tail);
            self.pending = 0;
        }
        let blocks = b.chunks_exact(32);
        let rest = blocks.remainder();
        for block in blocks {
            self.block(block);
        }
        self.tail[..rest.len()].copy_from_slice(rest);
        self.pending = rest.len();
    }

    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }

    pub fn finish(&self) -> u64 {
        let mut lanes = self.lanes;
        if self.pending > 0 {
            let mut last = [0u8; 32];
            last[..self.pending].copy_from_slice(&self.tail[..self.pending]);
            for (lane, w) in lanes.iter_mut().zip(last.chunks_exact(8)) {
                *lane = mix(*lane, u64::from_le_bytes(w.try_into().unwrap_or_default()));
            }
        }
        let h = lanes.iter().fold(0x8422_2325_cbf2_9ce4u64, |h, &l| mix(h, l));
        mix(h, self.len)
    }
}

const HEADER: usize = 24;

/// Writes `parts` joined as the payload under `magic` and `key` to `path` (directories created),
/// streamed (no joined copy in memory) to a temporary file that is renamed into place.
pub fn write(path: &Path, magic: &[u8; 8], key: u64, parts: &[&[u8]]) -> Result<()> {
    let dir = path.parent().context("cache path has no directory")?;
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let name = path.file_name().context("cache path has no file name")?.to_string_lossy();
    // Unique per process and call: two threads writing the same key must not share a temporary file.
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_file_name(format!("{name}.tmp{}-{n}", std::process::id()));
    let written = (|| {
        let mut f = std::io::BufWriter::with_capacity(1 << 20, std::fs::File::create(&tmp)?);
        let len: usize = parts.iter().map(|p| p.len()).sum();
        f.write_all(magic)?;
        f.write_all(&key.to_le_bytes())?;
        f.write_all(&(len as u64).to_le_bytes())?;
        let mut h = Hash64::default();
        for p in parts {
            h.bytes(p);
            f.write_all(p)?;
        }
        f.write_all(&h.finish().to_le_bytes())?;
        // No fsync: after a crash the reader's length and checksum checks catch a torn file.
        f.flush()
    })();
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(e).with_context(|| format!("writing {}", tmp.display()));
    }
    std::fs::rename(&tmp, path).with_context(|| format!("renaming {} to {}", tmp.display(), path.display()))
}

/// An open cache file whose header matched: its payload is read in parts into the caller's buffers
/// (no copy of the whole), and [`Reader::finish`] then checks that all of it was read and its hash.
pub struct Reader {
    file: std::fs::File,
    hash: Hash64,
    left: u64,
}

impl Reader {
    /// Opens the file at `path` if it carries `magic` and `key` and its size matches its header; an
    /// error saying which check failed otherwise.
    pub fn open(path: &Path, magic: &[u8; 8], key: u64) -> Result<Reader> {
        let mut file = std::fs::File::open(path).context("reading")?;
        let size = file.metadata().context("reading")?.len();
        ensure!(size >= HEADER as u64 + 8, "{size} bytes: truncated");
        let mut header = [0u8; HEADER];
        file.read_exact(&mut header).context("reading")?;
        ensure!(&header[..8] == magic, "not a cache file of this kind and version");
        let word = |o: usize| u64::from_le_bytes(header[o..o + 8].try_into().unwrap_or_default());
        ensure!(word(8) == key, "key {:016x}, expected {key:016x}", word(8));
        let len = word(16);
        ensure!(
            len == size - HEADER as u64 - 8,
            "{size} bytes, expected {} (truncated?)",
            len + HEADER as u64 + 8
        );
        Ok(Reader { file, hash: Hash64::default(), left: len })
    }

    /// Payload bytes not read yet.
    pub fn left(&self) -> u64 {
        self.left
    }

    /// Fills `buf` with the next payload bytes.
    pub fn read(&mut self, buf: &mut [u8]) -> Result<()> {
        ensure!(
            buf.len() as u64 <= self.left,
            "{} bytes asked, {} left in the payload",
            buf.len(),
            self.left
        );
        self.file.read_exact(buf).context("reading")?;
        self.hash.bytes(buf);
        self.left -= buf.len() as u64;
        Ok(())
    }

    /// Checks that the whole payload was read and matches its stored hash.
    pub fn finish(mut self) -> Result<()> {
        ensure!(self.left == 0, "{} payload bytes not read", self.left);
        let mut stored = [0u8; 8];
        self.file.read_exact(&mut stored).context("reading")?;
        ensure!(self.hash.finish() == u64::from_le_bytes(stored), "checksum mismatch");
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(test: &str) -> PathBuf {
        let d = std::env::temp_dir().join("hybrid-rt-tests").join(format!("disk-cache-{test}"));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn a_written_file_reads_back_and_every_damage_is_an_error() {
        let path = dir("damage").join("sub").join("x.bin");
        let payload: Vec<u8> = (0..1001u32).map(|i| (i * 7 % 251) as u8).collect();
        write(&path, b"TESTMAG1", 42, &[&payload[..300], &payload[300..]]).unwrap();
        let read = |p: &Path, magic: &[u8; 8], key| -> Result<Vec<u8>> {
            let mut r = Reader::open(p, magic, key)?;
            let mut out = vec![0u8; r.left() as usize];
            let (a, b) = out.split_at_mut(517);
            r.read(a)?;
            r.read(b)?;
            r.finish()?;
            Ok(out)
        };
        assert_eq!(read(&path, b"TESTMAG1", 42).unwrap(), payload);
        let err = |p: &Path, magic: &[u8; 8], key| format!("{:#}", read(p, magic, key).unwrap_err());
        // A reader that stops short is an error, not a silent success.
        let mut r = Reader::open(&path, b"TESTMAG1", 42).unwrap();
        r.read(&mut [0u8; 10]).unwrap();
        assert!(format!("{:#}", r.finish().unwrap_err()).contains("not read"));
        assert!(err(&path, b"TESTMAG2", 42).contains("not a cache file"));
        assert!(err(&path, b"TESTMAG1", 43).contains("key"));
        let whole = std::fs::read(&path).unwrap();
        for cut in [0, 20, 31, whole.len() / 2, whole.len() - 1] {
            std::fs::write(&path, &whole[..cut]).unwrap();
            let e = err(&path, b"TESTMAG1", 42);
            assert!(e.contains("truncated") || e.contains("not a cache file"), "cut at {cut}: {e}");
        }
        for at in [24, 500, whole.len() - 9, whole.len() - 1] {
            let mut bad = whole.clone();
            bad[at] ^= 0x10;
            std::fs::write(&path, &bad).unwrap();
            assert!(err(&path, b"TESTMAG1", 42).contains("checksum"), "flipped byte {at}");
        }
        assert!(err(&path.with_file_name("none.bin"), b"TESTMAG1", 42).contains("reading"));
        // No temporary file is left behind.
        assert_eq!(std::fs::read_dir(path.parent().unwrap()).unwrap().count(), 1);
    }

    #[test]
    fn the_hash_sees_every_byte_and_the_length() {
        let h = |b: &[u8]| {
            let mut h = Hash64::default();
            h.bytes(b);
            h.finish()
        };
        let base: Vec<u8> = (0..100u8).collect();
        let mut seen = std::collections::HashSet::new();
        assert!(seen.insert(h(&base)));
        for i in 0..base.len() {
            let mut b = base.clone();
            b[i] ^= 1;
            assert!(seen.insert(h(&b)), "flipping byte {i} left the hash unchanged");
        }
        // Streaming: parts hash as their join, whatever the boundaries.
        let parts = |cuts: &[usize]| {
            let mut h = Hash64::default();
            let mut at = 0;
            for &c in cuts.iter().chain([&base.len()]) {
                h.bytes(&base[at..c]);
                at = c;
            }
            h.finish()
        };
        for cuts in [&[][..], &[1], &[3, 5], &[7, 8, 9, 20, 33, 63]] {
            assert_eq!(parts(cuts), h(&base), "cuts {cuts:?}");
        }
        // Zero padding does not alias a shorter input with a longer one.
        assert_ne!(h(&[1, 2, 3]), h(&[1, 2, 3, 0]));
        assert_ne!(h(&[]), h(&[0]));
    }
}
