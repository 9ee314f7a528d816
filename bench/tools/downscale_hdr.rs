//! Box-filters an equirect Radiance .hdr down by an integer factor and writes
//! it as RGBE: how assets/potsdamer_platz_512.hdr was made from the Poly
//! Haven 1k map (assets/LICENSES.md).
//!
//! cargo run --example downscale_hdr -- IN.hdr OUT.hdr FACTOR

use anyhow::{bail, Context, Result};

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, output, factor] = args.as_slice() else {
        bail!("usage: downscale_hdr IN.hdr OUT.hdr FACTOR");
    };
    let f: u32 = factor.parse().ok().filter(|f| *f >= 1).context("FACTOR: an integer >= 1")?;
    let img = hybrid_rt::scene::scene_file::load_hdr(std::path::Path::new(input))?;
    let (w, h) = (img.width / f, img.height / f);
    if w == 0 || h == 0 {
        bail!("{input}: {}x{} is smaller than the factor {f}", img.width, img.height);
    }
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut sum = [0.0f64; 3];
            for sy in 0..f {
                for sx in 0..f {
                    let i = (((y * f + sy) * img.width + x * f + sx) * 3) as usize;
                    for (s, v) in sum.iter_mut().zip(&img.rgb[i..i + 3]) {
                        *s += *v as f64;
                    }
                }
            }
            let n = (f * f) as f64;
            pixels.push(image::Rgb(sum.map(|v| (v / n) as f32)));
        }
    }
    let file = std::fs::File::create(output).with_context(|| format!("cannot create {output}"))?;
    image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file))
        .encode(&pixels, w as usize, h as usize)
        .with_context(|| format!("writing {output}"))?;
    println!("{input} ({}x{}) -> {output} ({w}x{h})", img.width, img.height);
    Ok(())
}
