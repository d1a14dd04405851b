//! Loop subdivision of the Stanford bunny (69,451 triangles) to level 3 (4.44 million
//! triangles) with positions, normals and indices, against OpenSubdiv 3.5's
//! `Far::TopologyRefiner` + `Far::PrimvarRefiner` (the `osd_loop` oracle of
//! /work/shared/tools, run in the same process tree right before, when `HCE_OSD_LOOP` names it).
//!
//! `HCE_EXTRA_MESHES=/work/shared/meshes HCE_OSD_LOOP=/path/osd_loop cargo bench -p hce-geometry
//! --bench subdivide`

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};

fn opensubdiv_ms(osd: &str, mesh: &Path, level: u32) -> Option<f64> {
    let out = Command::new(osd)
        .arg(mesh)
        .arg(level.to_string())
        .arg("-")
        .output()
        .ok()?;
    // "osd: topology X ms, interpolate Y ms"
    let text = String::from_utf8_lossy(&out.stderr);
    let nums: Vec<f64> = text
        .split(|c: char| !(c.is_ascii_digit() || c == '.'))
        .filter_map(|s| s.parse().ok())
        .collect();
    (nums.len() >= 2).then(|| nums[0] + nums[1])
}

fn bench(c: &mut Criterion) {
    let Ok(dir) = std::env::var("HCE_EXTRA_MESHES") else {
        eprintln!(
            "HCE_EXTRA_MESHES is not set: the bunny benchmark needs the shared meshes folder"
        );
        return;
    };
    let path = Path::new(&dir).join("stanford-bunny.obj");
    let input = hce_meshio::load_mesh(&path).unwrap();
    let w = hce_geometry::weld(&input.positions, 0.0);
    let tris = w.triangles(&input.triangles);
    let build = || {
        hce_geometry::topology::build_control_mesh(&w.positions, &tris, None, &Default::default())
            .unwrap()
    };
    let topo = build();
    let level = 3;

    let mut g = c.benchmark_group("bunny_level3");
    g.sample_size(10);
    g.bench_function("subdivide_from_tables", |b| {
        b.iter(|| hce_geometry::subdivide::subdivide(&topo.mesh, level).unwrap())
    });
    let mut reused = hce_geometry::subdivide::Refined::default();
    g.bench_function("subdivide_into_reused_buffers", |b| {
        b.iter(|| hce_geometry::subdivide::subdivide_into(&topo.mesh, level, &mut reused).unwrap())
    });
    g.bench_function("tables", |b| b.iter(build));
    g.bench_function("tables_plus_subdivide", |b| {
        b.iter(|| hce_geometry::subdivide::subdivide(&build().mesh, level).unwrap())
    });
    g.finish();

    // Ratio against OpenSubdiv in the same run: best of 3 of each, same control mesh.
    if let Ok(osd) = std::env::var("HCE_OSD_LOOP") {
        let tmp = std::env::temp_dir().join(format!("hce-bench-{}.obj", std::process::id()));
        let mut s = String::new();
        for p in topo.mesh.positions.chunks(3) {
            s.push_str(&format!("v {:.9e} {:.9e} {:.9e}\n", p[0], p[1], p[2]));
        }
        for t in topo.mesh.triangles.chunks(3) {
            s.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
        }
        std::fs::write(&tmp, s).unwrap();
        let osd_ms = (0..3)
            .filter_map(|_| opensubdiv_ms(&osd, &tmp, level))
            .fold(f64::INFINITY, f64::min);
        let _ = std::fs::remove_file(&tmp);
        let ours = |f: &dyn Fn()| {
            (0..5)
                .map(|_| {
                    let t = Instant::now();
                    f();
                    t.elapsed().as_secs_f64() * 1e3
                })
                .fold(f64::INFINITY, f64::min)
        };
        let sub = ours(&|| {
            std::hint::black_box(hce_geometry::subdivide::subdivide(&topo.mesh, level).unwrap());
        });
        let mut buf = hce_geometry::subdivide::Refined::default();
        hce_geometry::subdivide::subdivide_into(&topo.mesh, level, &mut buf).unwrap();
        let buf = std::cell::RefCell::new(buf);
        let reuse = ours(&|| {
            hce_geometry::subdivide::subdivide_into(&topo.mesh, level, &mut buf.borrow_mut())
                .unwrap();
        });
        let tables = ours(&|| {
            std::hint::black_box(build());
        });
        let all = ours(&|| {
            std::hint::black_box(hce_geometry::subdivide::subdivide(&build().mesh, level).unwrap());
        });
        // The memory-bandwidth floor: writing the output's bytes once, on both cores, into
        // memory already mapped (as `subdivide_into` does) and into fresh memory (as
        // `subdivide` does, page faults included).
        let out = hce_geometry::subdivide::subdivide(&topo.mesh, level).unwrap();
        let bytes = out.positions.len() * 24 + out.indices.len() * 12;
        drop(out);
        let fill = |buf: &mut [u8]| {
            use rayon::prelude::*;
            buf.par_chunks_mut(1 << 20).for_each(|c| c.fill(1));
        };
        let mut warm = vec![0u8; bytes];
        fill(&mut warm);
        let warm_cell = std::cell::RefCell::new(warm);
        let warm_ms = ours(&|| fill(&mut warm_cell.borrow_mut()));
        drop(warm_cell);
        let fresh_ms = ours(&|| {
            let mut b = vec![0u8; bytes];
            fill(&mut b);
            std::hint::black_box(&b);
        });
        println!(
            "memory floor for {:.1} MB of output: {warm_ms:.1} ms into mapped memory ({:.1} GB/s), \
             {fresh_ms:.1} ms into fresh memory ({:.1} GB/s)",
            bytes as f64 / 1e6,
            bytes as f64 / warm_ms / 1e6,
            bytes as f64 / fresh_ms / 1e6
        );
        println!(
            "bunny level 3: OpenSubdiv {osd_ms:.1} ms (topology + interpolate, positions only, 1 thread); \
             hce {sub:.1} ms from tables ({:.1}x), {reuse:.1} ms into reused buffers ({:.1}x), \
             {all:.1} ms tables + subdivide ({:.1}x, tables alone {tables:.1} ms), \
             positions + normals + indices, {} threads",
            osd_ms / sub,
            osd_ms / reuse,
            osd_ms / all,
            rayon::current_num_threads()
        );
    } else {
        eprintln!("HCE_OSD_LOOP is not set: no OpenSubdiv comparison in this run");
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
