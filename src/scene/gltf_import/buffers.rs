//! Buffers (GLB BIN chunk, data URIs, external files) and the URIs of
//! buffers and images, resolved relative to the glTF file.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, ensure, Context, Result};

use super::quoted;

pub(super) fn load_buffers(
    doc: &gltf::Document,
    base: &Path,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>> {
    doc.buffers()
        .map(|buffer| {
            let what = || format!("buffer {}{}", buffer.index(), quoted(buffer.name()));
            let data = match buffer.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| anyhow!("GLB has no BIN chunk")),
                gltf::buffer::Source::Uri(uri) => read_uri(uri, base),
            }
            .with_context(what)?;
            ensure!(
                data.len() >= buffer.length(),
                "{}: holds {} bytes but byteLength is {}",
                what(),
                data.len(),
                buffer.length()
            );
            Ok(data)
        })
        .collect()
}

/// Reads a buffer or image URI: base64 data URIs, or files relative to the
/// glTF (percent-encoded, as the spec requires).
pub(super) fn read_uri(uri: &str, base: &Path) -> Result<Vec<u8>> {
    if uri.starts_with("data:") {
        // The crate's decoder only handles the data scheme on this path.
        let data = gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), None)
            .map_err(|e| anyhow!("invalid data URI: {e}"))?;
        return Ok(data.0);
    }
    let path = resolve_uri(uri, base)?;
    std::fs::read(&path).with_context(|| format!("cannot read '{}'", path.display()))
}

fn resolve_uri(uri: &str, base: &Path) -> Result<PathBuf> {
    let decoded = percent_decode(uri).with_context(|| format!("invalid URI '{uri}'"))?;
    if let Some(rest) = decoded.strip_prefix("file://").or_else(|| decoded.strip_prefix("file:")) {
        return Ok(PathBuf::from(rest));
    }
    ensure!(
        !decoded.contains("://"),
        "unsupported URI scheme in '{uri}' (only relative paths and data URIs)"
    );
    Ok(base.join(decoded))
}

fn percent_decode(s: &str) -> Result<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = s.get(i + 1..i + 3).context("truncated percent escape")?;
            out.push(u8::from_str_radix(hex, 16).with_context(|| format!("bad percent escape '%{hex}'"))?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).context("percent-decoded URI is not UTF-8")
}
