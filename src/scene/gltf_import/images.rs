//! Textures: `Scene::textures` slots per (image, sampler, colour space),
//! glTF samplers, and the images decoded once each, in parallel.

use std::path::{Path, PathBuf};

use anyhow::{ensure, Context, Result};
use gltf::texture::{MagFilter, MinFilter, WrappingMode};

use super::buffers::read_uri;
use crate::scene::{Filter, SamplerDesc, Texture, TextureRef, UvTransform, Wrap};

/// Assigns `Scene::textures` slots to (image, sampler, colour space)
/// combinations while materials are converted; images are decoded later in
/// one parallel pass.
#[derive(Default)]
pub(super) struct TextureSlots {
    keys: Vec<(usize, SamplerDesc, bool)>,
}

impl TextureSlots {
    /// `tex_coord` and `transform` as the reference gives them
    /// (KHR_texture_transform's texCoord already applied).
    pub(super) fn slot(
        &mut self,
        texture: gltf::Texture,
        tex_coord: u32,
        transform: UvTransform,
        srgb: bool,
        material: &str,
    ) -> TextureRef {
        if tex_coord != 0 {
            log::warn!(
                "material '{material}': texture {} uses TEXCOORD_{tex_coord}; only TEXCOORD_0 is loaded",
                texture.index()
            );
        }
        let key = (texture.source().index(), sampler_desc(&texture.sampler()), srgb);
        let index = self.keys.iter().position(|k| *k == key).unwrap_or_else(|| {
            self.keys.push(key);
            self.keys.len() - 1
        });
        TextureRef { texture: index, tex_coord, transform }
    }

    /// Decodes every image used by a slot (each once, on all cores) and
    /// returns the textures in slot order.
    pub(super) fn decode(
        &self,
        doc: &gltf::Document,
        base: &Path,
        buffers: &[Vec<u8>],
    ) -> Result<Vec<Texture>> {
        let mut used: Vec<usize> = self.keys.iter().map(|k| k.0).collect();
        used.sort_unstable();
        used.dedup();
        let images: Vec<gltf::Image> = doc.images().collect();
        let sources: Vec<ImageSource> = used.iter().map(|&i| ImageSource::new(&images[i], base)).collect();
        let mut decoded: Vec<Option<DecodedImage>> =
            decode_parallel(&sources, buffers)?.into_iter().map(Some).collect();
        // Pixels move into their image's last texture; only an image used
        // with several samplers or colour spaces is copied.
        let mut last_use = vec![0; used.len()];
        let positions: Vec<usize> = self.keys.iter().filter_map(|k| used.binary_search(&k.0).ok()).collect();
        ensure!(positions.len() == self.keys.len(), "internal error: texture image not decoded");
        for (slot, &k) in positions.iter().enumerate() {
            last_use[k] = slot;
        }
        let mut textures = Vec::with_capacity(self.keys.len());
        for (slot, (&k, &(_, sampler, srgb))) in positions.iter().zip(&self.keys).enumerate() {
            let image = if last_use[k] == slot { decoded[k].take() } else { decoded[k].clone() };
            let image = image.context("internal error: texture image used after its last use")?;
            let name = sources[k].name.clone();
            textures.push(Texture {
                name,
                width: image.width,
                height: image.height,
                rgba8: image.rgba8,
                srgb,
                sampler,
            });
        }
        Ok(textures)
    }
}

#[derive(Clone)]
struct DecodedImage {
    width: u32,
    height: u32,
    rgba8: Vec<u8>,
}

/// Where one image's encoded bytes live, detached from the document so the
/// decode threads need nothing but the buffers.
struct ImageSource {
    name: String,
    location: ImageLocation,
}

enum ImageLocation {
    /// A URI (file or data) relative to `base`.
    Uri { uri: String, base: PathBuf },
    /// A byte range of a buffer.
    View { buffer: usize, offset: usize, length: usize },
}

impl ImageSource {
    fn new(image: &gltf::Image, base: &Path) -> Self {
        match image.source() {
            gltf::image::Source::View { view, .. } => ImageSource {
                name: image.name().map_or_else(|| format!("image {}", image.index()), str::to_string),
                location: ImageLocation::View {
                    buffer: view.buffer().index(),
                    offset: view.offset(),
                    length: view.length(),
                },
            },
            gltf::image::Source::Uri { uri, .. } => {
                let short = if uri.starts_with("data:") { "data URI" } else { uri };
                ImageSource {
                    name: image.name().unwrap_or(short).to_string(),
                    location: ImageLocation::Uri { uri: uri.to_string(), base: base.to_path_buf() },
                }
            }
        }
    }

    fn decode(&self, buffers: &[Vec<u8>]) -> Result<DecodedImage> {
        let bytes = match &self.location {
            ImageLocation::Uri { uri, base } => read_uri(uri, base)?,
            &ImageLocation::View { buffer, offset, length } => buffers
                .get(buffer)
                .and_then(|b| b.get(offset..offset.checked_add(length)?))
                .context("image bufferView is out of range of its buffer")?
                .to_vec(),
        };
        // The image crate converts every layout (grey, grey-alpha, RGB,
        // 16-bit) to RGBA8; glTF only allows PNG and JPEG.
        let image = image::load_from_memory(&bytes).context("cannot decode image")?.into_rgba8();
        Ok(DecodedImage { width: image.width(), height: image.height(), rgba8: image.into_raw() })
    }
}

/// Decodes `sources` on up to all available cores; the first failure (in
/// source order) is returned.
fn decode_parallel(sources: &[ImageSource], buffers: &[Vec<u8>]) -> Result<Vec<DecodedImage>> {
    crate::progress::stage(format!("decoding {} textures", sources.len()));
    let done = std::sync::atomic::AtomicUsize::new(0);
    let results = crate::par::map(sources.len(), &[], |i| {
        let src = &sources[i];
        let r = src.decode(buffers).with_context(|| format!("image '{}'", src.name));
        crate::progress::percent(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1, sources.len());
        r
    })
    .context("decoding images")?;
    results.into_iter().collect()
}

fn sampler_desc(s: &gltf::texture::Sampler) -> SamplerDesc {
    let wrap = |w: WrappingMode| match w {
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::Repeat => Wrap::Repeat,
    };
    let (min_filter, mipmaps) = match s.min_filter() {
        // No filter given: the renderer's choice, and mipmaps avoid aliasing.
        None => (Filter::Linear, true),
        Some(MinFilter::Nearest) => (Filter::Nearest, false),
        Some(MinFilter::Linear) => (Filter::Linear, false),
        Some(MinFilter::NearestMipmapNearest | MinFilter::NearestMipmapLinear) => (Filter::Nearest, true),
        Some(MinFilter::LinearMipmapNearest | MinFilter::LinearMipmapLinear) => (Filter::Linear, true),
    };
    SamplerDesc {
        mag_filter: match s.mag_filter() {
            Some(MagFilter::Nearest) => Filter::Nearest,
            _ => Filter::Linear,
        },
        min_filter,
        mipmaps,
        wrap_u: wrap(s.wrap_s()),
        wrap_v: wrap(s.wrap_t()),
    }
}
