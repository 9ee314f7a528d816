//! `bench --scale` end to end: one process per size and backend, validation on in each (the
//! environment carries over), rows that add up, curves that grow with size, plots that decode.
use crate::cli::{bin, tmp as out_dir};

#[test]
fn bench_scale_measures_every_size_and_backend_and_writes_csv_and_plots() {
    let dir = out_dir("scale");
    let out = bin()
        .args(["bench", "--scale", "--scale-max-triangles", "30000", "--scale-max-instances", "10"])
        .args(["--scale-frames", "1", "--width", "64", "--height", "36", "--scale-out"])
        .arg(&dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench --scale failed:\n{stderr}");
    // Progress per measurement on stderr, the table on stdout.
    assert!(stderr.contains("[8/8] instanced:10"), "{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        stdout.lines().filter(|l| l.starts_with("| unique") || l.starts_with("| instanced")).count(),
        8
    );

    let csv = std::fs::read_to_string(dir.join("scale.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no {name}"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 8, "2 unique sizes + 2 instance counts, compute and query:\n{csv}");
    let num = |r: &Vec<&str>, name: &str| -> f64 { r[col(name)].parse().unwrap() };
    for r in &rows {
        let (series, size, backend) = (r[col("series")], num(r, "size"), r[col("backend")]);
        let what = format!("{series} {size} {backend}");
        assert!(backend == "compute" || backend == "query", "{what}");
        let tris = num(r, "triangles");
        if series == "unique" {
            // The terrain within one cell row of the request, plus the sphere.
            assert!((tris - size).abs() < 2.0 * (size / 2.0).sqrt() + 4.0, "{what}: {tris} triangles");
            assert_eq!(num(r, "instances"), 2.0, "{what}");
        } else {
            assert_eq!(tris, 2.0 + 12.0 * size, "{what}: ground + a 12-triangle box per instance");
            assert_eq!(num(r, "instances"), size + 1.0, "{what}");
        }
        for name in
            ["upload_ms", "frame_ms", "peak_rss_bytes", "vertices_bytes", "indices_bytes", "accel_bytes"]
        {
            assert!(num(r, name) > 0.0, "{what}: {name} = {}", num(r, name));
        }
        // A process of its own: at least the Vulkan device and the scene, far below a leak.
        let rss = num(r, "peak_rss_bytes");
        assert!(rss > 20e6 && rss < 2e9, "{what}: peak RSS {rss}");
        let sum =
            ["generate_ms", "upload_ms", "accel_ms", "first_frame_ms"].iter().map(|n| num(r, n)).sum::<f64>();
        assert!((num(r, "load_ms") - sum).abs() < 0.01, "{what}: load is the stages' sum");
        let per_tri = (num(r, "vertices_bytes") + num(r, "indices_bytes") + num(r, "accel_bytes"))
            / num(r, "triangles");
        assert!((num(r, "bytes_per_triangle") - per_tri).abs() < 0.01, "{what}");
        assert!(r[col("passes_ms")].contains("gbuffer="), "{what}: per-pass ms");
        if series == "unique" && backend == "compute" {
            // Half a 48-byte vertex + 12 index bytes + the flat tree's ~56: 80-110 per triangle.
            assert!((80.0..110.0).contains(&per_tri), "{what}: {per_tri} B per triangle");
        }
    }
    // The structure grows with the size on both backends.
    for backend in ["compute", "query"] {
        let accel = |size: &str| {
            let r = rows.iter().find(|r| r[0] == "unique" && r[1] == size && r[2] == backend).unwrap();
            num(r, "accel_bytes")
        };
        assert!(accel("30000") > 2.0 * accel("10000"), "{backend}: {} vs {}", accel("30000"), accel("10000"));
    }
    for plot in ["unique_time", "unique_memory", "instanced_time", "instanced_memory"] {
        let img = image::open(dir.join(format!("{plot}.png"))).unwrap_or_else(|e| panic!("{plot}: {e}"));
        assert_eq!((img.width(), img.height()), (1200, 760), "{plot}");
        // Drawn on: far from a blank white page.
        let dark = img.to_luma8().pixels().filter(|p| p.0[0] < 128).count();
        assert!(dark > 5000, "{plot}: {dark} dark pixels");
    }
}

#[test]
fn bench_scale_with_no_size_left_fails_clearly() {
    let out = bin()
        .args(["bench", "--scale", "--scale-max-triangles", "5", "--scale-max-instances", "0", "--scale-out"])
        .arg(out_dir("scale-none"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("leave no size to measure") && !stderr.contains("panicked"), "{stderr}");
}

/// `bench --builders`: every builder's row per scene (the split BVH only up to its size limit), build
/// times and SAH costs that are numbers, the LBVH's host and device trees of equal cost (the same
/// tree), the device's steps timed; validation on; a bad scene spec is a clear CLI error.
#[test]
fn bench_builders_puts_the_builders_side_by_side() {
    let out = bin().args(["bench", "--builders", "unique:20000,instanced:50"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "bench --builders failed:\n{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<Vec<&str>> = stdout
        .lines()
        .filter(|l| l.starts_with("| unique") || l.starts_with("| instanced"))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    // Per scene: binned, split (both small enough), host LBVH, device LBVH.
    assert_eq!(rows.len(), 8, "{stdout}");
    for scene in ["unique:20000", "instanced:50"] {
        let mine: Vec<&Vec<&str>> = rows.iter().filter(|r| r[1] == scene).collect();
        let builders: Vec<&str> = mine.iter().map(|r| r[3]).collect();
        assert_eq!(
            builders,
            [
                "binned SAH (host, every core)",
                "split BVH (host, every core)",
                "LBVH (host, one thread)",
                "LBVH (device)"
            ],
            "{scene}"
        );
        let num = |r: &Vec<&str>, k: usize| r[k].parse::<f64>().unwrap_or_else(|_| panic!("{scene}: {r:?}"));
        for r in &mine {
            assert!(num(r, 4) > 0.0 && num(r, 5) > 0.0 && num(r, 6) > 0.0, "{scene}: {r:?}");
        }
        assert_eq!(mine[2][6], mine[3][6], "{scene}: host and device LBVH are one tree");
        assert!(num(mine[0], 6) < num(mine[2], 6), "{scene}: the SAH build beats Morton order");
        assert!(mine[3][7].contains("sort") && mine[3][7].contains("bounds"), "{scene}: {:?}", mine[3]);
    }
    let bad = bin().args(["bench", "--builders", "unique:0"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && stderr.contains("unique"), "{stderr}");
}
