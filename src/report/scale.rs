//! `bench --scale`: cost against size (issue 36 item 1). Generated scenes (`scene::generated`) of 1e4
//! to 1e7 unique triangles and of 1 to 1e6 instances of one mesh, each size and backend measured in a
//! process of its own (so peak host RSS is that size's): load stages in ms (generate, upload,
//! acceleration build, first frame), per-pass GPU ms of the measured frames, peak RSS, GPU memory by
//! category (used bytes of the buffers and images, not the allocator's blocks) and bytes per triangle.
//! Prints a table and writes `scale.csv` and log-log plots to the output folder.

use std::ffi::OsString;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use anyhow::{bail, Context as _, Result};

use super::measure::median_p95;
use super::plot::{log_curves, Series};
use crate::app::{with_context, GpuOptions, RenderJob};
use crate::csv::{csv_field, csv_number};
use crate::render::shading::Backend;
use crate::render::Renderer;
use crate::scene::{generated, Scene};

/// The unique series' sizes (triangles) and the instanced series' counts, each up to its maximum.
pub const UNIQUE_SIZES: [u64; 7] = [10_000, 30_000, 100_000, 300_000, 1_000_000, 3_000_000, 10_000_000];
pub const INSTANCE_COUNTS: [u64; 7] = [1, 10, 100, 1_000, 10_000, 100_000, 1_000_000];

/// The line prefix a measuring child prints its row after.
const ROW_TAG: &str = "SCALE-ROW\t";

/// One generated scene: `unique:N` (N unique triangles) or `instanced:N` (N placements of one mesh).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Point {
    Unique(u64),
    Instanced(u64),
}

impl Point {
    pub fn scene(self) -> Result<Scene> {
        match self {
            Point::Unique(n) => generated::unique(n),
            Point::Instanced(n) => generated::instanced(n),
        }
    }

    fn series(self) -> &'static str {
        match self {
            Point::Unique(_) => "unique",
            Point::Instanced(_) => "instanced",
        }
    }

    fn size(self) -> u64 {
        match self {
            Point::Unique(n) | Point::Instanced(n) => n,
        }
    }
}

impl fmt::Display for Point {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.series(), self.size())
    }
}

impl FromStr for Point {
    type Err = anyhow::Error;
    fn from_str(s: &str) -> Result<Point> {
        let (series, n) = s.split_once(':').context("expected unique:N or instanced:N")?;
        let n: u64 = n.parse().with_context(|| format!("{n:?} is not a count"))?;
        match series {
            "unique" => Ok(Point::Unique(n)),
            "instanced" => Ok(Point::Instanced(n)),
            _ => bail!("unknown series {series:?} (unique or instanced)"),
        }
    }
}

/// What one size on one backend cost.
#[derive(Clone, Debug, PartialEq)]
pub struct ScaleRow {
    pub point: Point,
    pub backend: String,
    pub instances: u64,
    /// Triangles as placed (each instance's).
    pub triangles: u64,
    /// Triangles stored once per mesh.
    pub unique_triangles: u64,
    pub generate_ms: f64,
    pub upload_ms: f64,
    /// The tracer's acceleration-structure build (inside the first frame).
    pub accel_ms: f64,
    /// The first frame without the build: pipelines on first use, first draws and traces.
    pub first_frame_ms: f64,
    /// Median GPU ms of the measured frames, and per pass.
    pub frame_ms: f64,
    pub passes: Vec<(String, f64)>,
    pub peak_rss: u64,
    pub vertices: u64,
    pub indices: u64,
    pub textures: u64,
    /// Environment, PRT, shadow maps, materials, instances, lights, per-frame buffers.
    pub other: u64,
    pub accel: u64,
    pub targets: u64,
}

impl ScaleRow {
    /// Vertices, indices and acceleration structure per placed triangle.
    pub fn bytes_per_triangle(&self) -> f64 {
        (self.vertices + self.indices + self.accel) as f64 / self.triangles.max(1) as f64
    }

    pub fn gpu_bytes(&self) -> u64 {
        self.vertices + self.indices + self.textures + self.other + self.accel + self.targets
    }

    pub fn load_ms(&self) -> f64 {
        self.generate_ms + self.upload_ms + self.accel_ms + self.first_frame_ms
    }

    pub const CSV_HEADER: &'static str =
        "series,size,backend,instances,triangles,unique_triangles,generate_ms,\
upload_ms,accel_ms,first_frame_ms,load_ms,frame_ms,peak_rss_bytes,vertices_bytes,indices_bytes,\
textures_bytes,other_bytes,accel_bytes,targets_bytes,gpu_bytes,bytes_per_triangle,passes_ms";

    pub fn csv(&self) -> String {
        let ms = |v: f64| csv_number(v, 3);
        let passes: Vec<String> = self.passes.iter().map(|(n, v)| format!("{n}={v:.3}")).collect();
        [
            self.point.series().to_string(),
            self.point.size().to_string(),
            csv_field(&self.backend),
            self.instances.to_string(),
            self.triangles.to_string(),
            self.unique_triangles.to_string(),
            ms(self.generate_ms),
            ms(self.upload_ms),
            ms(self.accel_ms),
            ms(self.first_frame_ms),
            ms(self.load_ms()),
            ms(self.frame_ms),
            self.peak_rss.to_string(),
            self.vertices.to_string(),
            self.indices.to_string(),
            self.textures.to_string(),
            self.other.to_string(),
            self.accel.to_string(),
            self.targets.to_string(),
            self.gpu_bytes().to_string(),
            csv_number(self.bytes_per_triangle(), 2),
            csv_field(&passes.join(";")),
        ]
        .join(",")
    }

    /// The child's line back into a row (the fields `csv` wrote; derived ones are recomputed).
    pub fn parse(line: &str) -> Result<ScaleRow> {
        let f: Vec<&str> = line.split(',').collect();
        let want = Self::CSV_HEADER.split(',').count();
        anyhow::ensure!(f.len() == want, "{} fields, expected {want}: {line}", f.len());
        let n = |i: usize| f[i].parse::<u64>().with_context(|| format!("field {i} of {line}"));
        let x = |i: usize| f[i].parse::<f64>().with_context(|| format!("field {i} of {line}"));
        let passes = f[want - 1]
            .split(';')
            .filter(|p| !p.is_empty())
            .map(|p| {
                let (name, v) = p.split_once('=').context("pass=ms")?;
                Ok((name.to_string(), v.parse::<f64>()?))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(ScaleRow {
            point: format!("{}:{}", f[0], f[1]).parse()?,
            backend: f[2].to_string(),
            instances: n(3)?,
            triangles: n(4)?,
            unique_triangles: n(5)?,
            generate_ms: x(6)?,
            upload_ms: x(7)?,
            accel_ms: x(8)?,
            first_frame_ms: x(9)?,
            frame_ms: x(11)?,
            peak_rss: n(12)?,
            vertices: n(13)?,
            indices: n(14)?,
            textures: n(15)?,
            other: n(16)?,
            accel: n(17)?,
            targets: n(18)?,
            passes,
        })
    }
}

/// This process's peak resident set (Linux `VmHWM`), 0 where unknown.
pub fn peak_rss() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        .map_or(0, |kb| kb * 1024)
}

/// The child's side: generates `point`, loads it and renders `frames` measured frames (after two
/// unmeasured) with `job`'s settings and size on `job.settings.backend`; prints the row.
pub fn measure_point(gpu: &GpuOptions, point: Point, job: &RenderJob, frames: usize) -> Result<()> {
    let row = with_context(gpu, |ctx| {
        let load = crate::progress::begin();
        let t = std::time::Instant::now();
        let scene = point.scene()?;
        let generate_ms = t.elapsed().as_secs_f64() * 1e3;
        let camera = scene.cameras[0].clone();
        crate::app::resolve_shading(ctx, &scene, &job.settings)?;
        let t = std::time::Instant::now();
        let mut renderer = Renderer::new(ctx, &scene, job.extent()?)?;
        let upload_ms = t.elapsed().as_secs_f64() * 1e3;
        let measured = (|| -> Result<ScaleRow> {
            let t = std::time::Instant::now();
            renderer.render(ctx, &scene, &camera, &job.settings)?;
            let first_ms = t.elapsed().as_secs_f64() * 1e3;
            drop(load);
            let stats = renderer.accel_stats().unwrap_or_default();
            let mut totals = Vec::new();
            let mut passes: Vec<(String, Vec<f64>)> = Vec::new();
            for i in 0..frames + 2 {
                let f = renderer.render(ctx, &scene, &camera, &job.settings)?;
                if i < 2 {
                    continue;
                }
                totals.push(f.timings.iter().map(|t| t.1).sum::<f64>());
                for (name, ms) in f.timings {
                    match passes.iter_mut().find(|p| p.0 == name) {
                        Some(p) => p.1.push(ms),
                        None => passes.push((name.to_string(), vec![ms])),
                    }
                }
            }
            if let Some(b) = renderer.budget_report() {
                log::info!("{}", b.summary());
            }
            let memory = renderer.scene_memory();
            let triangles = |inst: &crate::scene::Instance| {
                scene.meshes[inst.mesh].primitives[inst.primitive].indices.len() as u64 / 3
            };
            Ok(ScaleRow {
                point,
                backend: renderer
                    .shading_config()
                    .and_then(|c| c.backend)
                    .map_or("none", backend_arg)
                    .to_string(),
                instances: scene.instances.len() as u64,
                triangles: scene.instances.iter().map(triangles).sum(),
                unique_triangles: scene
                    .meshes
                    .iter()
                    .flat_map(|m| &m.primitives)
                    .map(|p| p.indices.len() as u64 / 3)
                    .sum(),
                generate_ms,
                upload_ms,
                accel_ms: stats.build_ms,
                first_frame_ms: (first_ms - stats.build_ms).max(0.0),
                frame_ms: median_p95(&totals).0,
                passes: passes.into_iter().map(|(n, v)| (n, median_p95(&v).0)).collect(),
                peak_rss: 0,
                vertices: memory.vertices,
                indices: memory.indices,
                textures: memory.textures,
                other: memory.environment + memory.prt + memory.shadow_maps + memory.other,
                accel: stats.bytes,
                targets: renderer.target_bytes(),
            })
        })();
        renderer.destroy(ctx);
        let row = measured?;
        crate::app::check_validation(ctx)?;
        Ok(row)
    })?;
    let row = ScaleRow { peak_rss: peak_rss(), ..row };
    println!("{ROW_TAG}{}", row.csv());
    Ok(())
}

/// What `bench --scale` measures and where it writes.
pub struct ScaleOptions {
    pub max_triangles: u64,
    pub max_instances: u64,
    pub out: PathBuf,
    /// The backends to measure (each a child per size).
    pub backends: Vec<Backend>,
}

/// The points up to the maxima, unique series first.
pub fn points(max_triangles: u64, max_instances: u64) -> Vec<Point> {
    let unique = UNIQUE_SIZES.iter().filter(|&&n| n <= max_triangles).map(|&n| Point::Unique(n));
    let instanced = INSTANCE_COUNTS.iter().filter(|&&n| n <= max_instances).map(|&n| Point::Instanced(n));
    unique.chain(instanced).collect()
}

/// The child's arguments: this process's, less the scale options and any `--backend`, plus the point
/// and the backend. So every other setting (size, effects, budget, device, log level) carries over.
pub fn child_args(args: &[OsString], point: Point, backend: Backend) -> Vec<OsString> {
    const WITH_VALUE: [&str; 5] =
        ["--scale-max-triangles", "--scale-max-instances", "--scale-out", "--backend", "--scale-point"];
    let mut out = Vec::new();
    let mut skip = false;
    for a in args {
        if std::mem::take(&mut skip) {
            continue;
        }
        let s = a.to_string_lossy();
        if s == "--scale" || WITH_VALUE.iter().any(|w| s.starts_with(&format!("{w}="))) {
            continue;
        }
        if WITH_VALUE.contains(&s.as_ref()) {
            skip = true;
            continue;
        }
        out.push(a.clone());
    }
    // The children's info lines would bury the progress: warnings only, unless a level was asked for.
    if !args.iter().any(|a| a.to_string_lossy().starts_with("--log")) {
        out.splice(0..0, ["--log".into(), "warn".into()]);
    }
    out.extend(["--scale-point".into(), point.to_string().into(), "--backend".into()]);
    out.push(backend_arg(backend).into());
    out
}

fn backend_arg(b: Backend) -> &'static str {
    match b {
        Backend::Auto => "auto",
        Backend::Query => "query",
        Backend::Pipeline => "pipeline",
        Backend::Compute => "compute",
    }
}

/// The parent's side: one child process per point and backend, the table, `scale.csv` and the plots.
pub fn scale_command(opts: &ScaleOptions) -> Result<Vec<ScaleRow>> {
    let exe = std::env::current_exe().context("finding this program to run the sizes")?;
    let args: Vec<OsString> = std::env::args_os().skip(1).collect();
    let points = points(opts.max_triangles, opts.max_instances);
    anyhow::ensure!(
        !points.is_empty(),
        "--scale-max-triangles and --scale-max-instances leave no size to measure"
    );
    std::fs::create_dir_all(&opts.out).with_context(|| format!("creating {}", opts.out.display()))?;
    let total = points.len() * opts.backends.len();
    let mut rows = Vec::new();
    let mut failed = Vec::new();
    let start = std::time::Instant::now();
    for (k, (point, backend)) in
        points.iter().flat_map(|p| opts.backends.iter().map(move |b| (*p, *b))).enumerate()
    {
        eprintln!("bench --scale: [{}/{total}] {point} on the {} backend ...", k + 1, backend_arg(backend));
        let t = std::time::Instant::now();
        let mut child = std::process::Command::new(&exe);
        // Every size builds its structures (set the variable to measure the cache instead).
        if std::env::var_os(crate::accel::flat_cache::CACHE_DIR_ENV).is_none() {
            child.env(crate::accel::flat_cache::CACHE_DIR_ENV, "off");
        }
        let out = child
            .args(child_args(&args, point, backend))
            .stderr(std::process::Stdio::inherit())
            .output()
            .with_context(|| format!("running {}", exe.display()))?;
        let stdout = String::from_utf8_lossy(&out.stdout);
        let row = stdout.lines().find_map(|l| l.strip_prefix(ROW_TAG)).map(ScaleRow::parse);
        match (out.status.success(), row) {
            (true, Some(Ok(row))) => {
                eprintln!(
                    "bench --scale: [{}/{total}] {point} {}: load {:.0} ms, frame {:.1} ms, peak RSS {:.0} MB ({:.1} s)",
                    k + 1,
                    row.backend,
                    row.load_ms(),
                    row.frame_ms,
                    row.peak_rss as f64 / 1e6,
                    t.elapsed().as_secs_f64()
                );
                rows.push(row);
            }
            (_, Some(Err(e))) => failed.push(format!("{point} {}: bad row: {e:#}", backend_arg(backend))),
            (ok, None) => failed.push(format!(
                "{point} {}: {} without a row",
                backend_arg(backend),
                if ok { "exited" } else { "failed" }
            )),
            (false, Some(Ok(_))) => {
                failed.push(format!("{point} {}: failed after its row", backend_arg(backend)))
            }
        }
    }
    println!("{}", table(&rows));
    write(&opts.out, &rows)?;
    eprintln!("bench --scale: {total} measurements in {:.0} s", start.elapsed().as_secs_f64());
    if !failed.is_empty() {
        bail!("bench --scale: {} of {total} sizes failed: {}", failed.len(), failed.join("; "));
    }
    Ok(rows)
}

/// The markdown table of every row.
pub fn table(rows: &[ScaleRow]) -> String {
    let mut s = String::from(
        "| series | size | backend | triangles | instances | generate ms | upload ms | accel build ms | \
         first frame ms | frame ms | peak RSS MB | GPU MB | B/triangle |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.0} | {:.2} | {:.0} | {:.1} | {:.1} |\n",
            r.point.series(),
            r.point.size(),
            r.backend,
            r.triangles,
            r.instances,
            r.generate_ms,
            r.upload_ms,
            r.accel_ms,
            r.first_frame_ms,
            r.frame_ms,
            r.peak_rss as f64 / 1e6,
            r.gpu_bytes() as f64 / 1e6,
            r.bytes_per_triangle()
        ));
    }
    s
}

/// `scale.csv` and, per series, a time and a memory plot on log-log axes.
fn write(dir: &Path, rows: &[ScaleRow]) -> Result<()> {
    let mut csv = format!("{}\n", ScaleRow::CSV_HEADER);
    for r in rows {
        csv.push_str(&r.csv());
        csv.push('\n');
    }
    let path = dir.join("scale.csv");
    std::fs::write(&path, csv).with_context(|| format!("writing {}", path.display()))?;
    let mut written = vec![path];
    for (series, x_desc) in
        [("unique", "unique triangles"), ("instanced", "instances of one 12-triangle mesh")]
    {
        let rows: Vec<&ScaleRow> = rows.iter().filter(|r| r.point.series() == series).collect();
        if rows.is_empty() {
            continue;
        }
        let mut backends: Vec<&str> = Vec::new();
        for r in &rows {
            if !backends.contains(&r.backend.as_str()) {
                backends.push(&r.backend);
            }
        }
        let curve = |label: String, b: &str, y: &dyn Fn(&ScaleRow) -> f64| Series {
            label,
            points: rows
                .iter()
                .filter(|r| r.backend == b)
                .map(|r| (r.point.size() as f64, y(r), String::new()))
                .collect(),
        };
        let mut time = Vec::new();
        let mut memory = Vec::new();
        for b in &backends {
            time.push(curve(format!("{b}: load (generate to first frame)"), b, &|r| r.load_ms()));
            time.push(curve(format!("{b}: acceleration build"), b, &|r| r.accel_ms));
            time.push(curve(format!("{b}: frame (GPU)"), b, &|r| r.frame_ms));
            memory.push(curve(format!("{b}: peak host RSS"), b, &|r| r.peak_rss as f64 / 1e6));
            memory.push(curve(format!("{b}: GPU memory in use"), b, &|r| r.gpu_bytes() as f64 / 1e6));
            memory.push(curve(format!("{b}: acceleration structure"), b, &|r| r.accel as f64 / 1e6));
        }
        let p = dir.join(format!("{series}_time.png"));
        log_curves(&p, &format!("Cost against size: {series} series, time"), x_desc, "milliseconds", &time)?;
        written.push(p);
        let p = dir.join(format!("{series}_memory.png"));
        log_curves(&p, &format!("Cost against size: {series} series, memory"), x_desc, "megabytes", &memory)?;
        written.push(p);
    }
    for p in written {
        eprintln!("bench --scale: wrote {}", p.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row() -> ScaleRow {
        ScaleRow {
            point: Point::Instanced(1000),
            backend: "compute".into(),
            instances: 1001,
            triangles: 12002,
            unique_triangles: 14,
            generate_ms: 1.5,
            upload_ms: 20.25,
            accel_ms: 3.0,
            first_frame_ms: 400.0,
            frame_ms: 12.5,
            passes: vec![("gbuffer".into(), 5.25), ("direct".into(), 7.25)],
            peak_rss: 123_456_789,
            vertices: 1152,
            indices: 168,
            textures: 0,
            other: 4096,
            accel: 8000,
            targets: 84 * 320 * 180,
        }
    }

    #[test]
    fn rows_go_through_the_child_line_unchanged() {
        let r = row();
        let line = r.csv();
        assert_eq!(line.split(',').count(), ScaleRow::CSV_HEADER.split(',').count());
        assert_eq!(ScaleRow::parse(&line).unwrap(), r);
        assert!((r.bytes_per_triangle() - (1152.0 + 168.0 + 8000.0) / 12002.0).abs() < 1e-9);
        assert_eq!(r.load_ms(), 1.5 + 20.25 + 3.0 + 400.0);
        assert!(ScaleRow::parse("unique,1,compute").is_err());
        for p in ["unique:10000", "instanced:7"] {
            assert_eq!(p.parse::<Point>().unwrap().to_string(), p);
        }
        assert!("triangles:5".parse::<Point>().is_err());
        assert!("unique:x".parse::<Point>().is_err());
    }

    #[test]
    fn sizes_stop_at_the_maxima() {
        let p = points(100_000, 10);
        assert_eq!(
            p,
            vec![
                Point::Unique(10_000),
                Point::Unique(30_000),
                Point::Unique(100_000),
                Point::Instanced(1),
                Point::Instanced(10)
            ]
        );
        assert_eq!(points(0, 1_000_000).len(), INSTANCE_COUNTS.len());
    }

    #[test]
    fn a_child_gets_every_setting_but_the_scale_options_and_the_backend() {
        let args: Vec<OsString> = [
            "--log",
            "info",
            "bench",
            "--scale",
            "--width",
            "320",
            "--backend",
            "query",
            "--scale-max-triangles=1000",
            "--scale-out",
            "o",
            "--budget-ms",
            "5",
            "--scale-frames",
            "2",
        ]
        .iter()
        .map(|s| OsString::from(*s))
        .collect();
        let child = child_args(&args, Point::Unique(10_000), Backend::Compute);
        let child: Vec<String> = child.iter().map(|s| s.to_string_lossy().into_owned()).collect();
        assert_eq!(
            child,
            [
                "--log",
                "info",
                "bench",
                "--width",
                "320",
                "--budget-ms",
                "5",
                "--scale-frames",
                "2",
                "--scale-point",
                "unique:10000",
                "--backend",
                "compute"
            ]
        );
    }
}
