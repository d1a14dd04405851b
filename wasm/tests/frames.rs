//! The interface natively: what `load` and `tables` return for the conformance suite's files,
//! against the crates they wrap called directly, and damaged input as an error value.

use std::path::{Path, PathBuf};

use hce_format::ObjectKind;
use hce_geometry::adaptive_flat::refine_adaptive_flat;
use hce_geometry::lighting::{LightingTable, Reconstruction};
use hce_geometry::loop_tables::LoopKernelTables;
use hce_geometry::refine::{refine_object_as, FlatRefinement};
use hce_runtime::Asset;
use hce_wasm::{load, refine, tables, Reader, Writer};

fn conformance(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../conformance")
        .join(file)
}

fn load_request(name: &str, bytes: &[u8]) -> Vec<u32> {
    let mut w = Writer::default();
    w.string(name);
    w.u32(1);
    w.bytes(bytes);
    w.u32(0);
    w.finish()
}

#[test]
fn a_damaged_container_is_the_loaders_error_without_the_file_name() {
    let path = conformance("valid/triangle.hce");
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[40] ^= 1;
    let dir = tempfile_dir();
    let damaged = dir.join("t.hce");
    std::fs::write(&damaged, &bytes).unwrap();
    let native = Asset::open(&damaged).unwrap_err().to_string();
    let got = load(&load_request("t.hce", &bytes)).unwrap_err();
    assert_eq!(format!("{}: {got}", damaged.display()), native);
    assert!(got.contains("checksum"), "{got}");
    std::fs::remove_dir_all(dir).unwrap();
}

fn tempfile_dir() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("hce-wasm-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn truncated_requests_are_errors_not_traps() {
    let request = load_request("a.glb", b"glTF\x02\0\0\0");
    for n in 0..request.len() {
        assert!(load(&request[..n]).is_err(), "{n} words");
    }
    assert!(tables(&[]).is_err());
    assert!(tables(&[0, 5]).is_err());
    assert!(refine(&[]).is_err());
    assert!(refine(&[0, 5]).is_err());
}

/// Each object's words as `load` writes them (from `name` to `corner_colours`), with its index.
fn object_frames(file: &str) -> Vec<(u32, Vec<u32>)> {
    let bytes = std::fs::read(conformance(file)).unwrap();
    let asset = Asset::open(conformance(file)).unwrap();
    let out = load(&load_request(file, &bytes)).unwrap();
    let mut r = Reader::new(&out);
    r.u32().unwrap();
    r.string().unwrap();
    for _ in 0..r.u32().unwrap() {
        r.string().unwrap();
    }
    if r.u32().unwrap() == 1 {
        r.string().unwrap();
        for _ in 0..3 {
            r.floats().unwrap();
        }
        r.f32_bits().unwrap();
        r.u32().unwrap();
        r.f32_bits().unwrap();
    }
    assert_eq!(r.u32().unwrap() as usize, asset.objects.len());
    let mut frames = Vec::new();
    for _ in &asset.objects {
        let index = r.u32().unwrap();
        let start = r.position();
        r.string().unwrap();
        for _ in 0..5 {
            r.u32().unwrap();
        }
        r.floats().unwrap();
        for _ in 0..13 {
            r.words().unwrap();
        }
        frames.push((index, out[start..r.position()].to_vec()));
        r.u32().unwrap();
        r.floats().unwrap();
        r.f32_bits().unwrap();
        for _ in 0..r.u32().unwrap() {
            r.u32().unwrap();
            r.string().unwrap();
            r.floats().unwrap();
        }
    }
    frames
}

/// A `refine` request: index, object words, level, reconstruction, flat refinement.
fn refine_request(
    index: u32,
    object: &[u32],
    level: u32,
    reconstruction: u32,
    flat: u32,
) -> Vec<u32> {
    let mut request = vec![index];
    request.extend_from_slice(object);
    request.extend([level, reconstruction, flat]);
    request
}

#[test]
fn refine_is_hce_subdivides_refinement() {
    // The Cornell box: flat walls and a multiresolution block.
    let asset = Asset::open(conformance("valid/cornell-box.glb")).unwrap();
    let frames = object_frames("valid/cornell-box.glb");
    for ((index, words), o) in frames.iter().zip(&asset.objects) {
        for (level, reconstruction, code, flat, flat_code) in [
            (0, Reconstruction::Smooth, 0, FlatRefinement::Uniform, 1),
            (2, Reconstruction::Smooth, 0, FlatRefinement::Uniform, 1),
            (
                1,
                Reconstruction::NearestNormal,
                1,
                FlatRefinement::Uniform,
                1,
            ),
            (1, Reconstruction::Gouraud, 2, FlatRefinement::Uniform, 1),
            (2, Reconstruction::Smooth, 0, FlatRefinement::Adaptive, 0),
            (1, Reconstruction::Gouraud, 2, FlatRefinement::Adaptive, 0),
        ] {
            let out = refine(&refine_request(*index, words, level, code, flat_code)).unwrap();
            let native = refine_object_as(&o.object, level, reconstruction, flat).unwrap();
            let mut r = Reader::new(&out);
            assert_eq!(r.u32().unwrap(), native.mesh.level);
            let bits = |v: &[[f32; 3]]| -> Vec<u32> {
                v.as_flattened().iter().map(|x| x.to_bits()).collect()
            };
            let got = |r: &mut Reader| -> Vec<u32> {
                r.floats().unwrap().iter().map(|x| x.to_bits()).collect()
            };
            assert_eq!(
                got(&mut r),
                bits(&native.mesh.positions),
                "{} level {level}",
                o.object.name
            );
            assert_eq!(got(&mut r), bits(&native.mesh.normals));
            assert_eq!(got(&mut r), bits(&native.colours));
            assert_eq!(r.words().unwrap(), native.mesh.indices.as_flattened());
            let starts: Vec<u32> = native.triangle_start.iter().map(|&s| s as u32).collect();
            assert_eq!(r.words().unwrap(), starts);
        }
    }
    let (index, words) = &frames[0];
    let deep = refine(&refine_request(*index, words, 7, 0, 1)).unwrap_err();
    assert!(deep.contains("level 7"), "{deep}");
    let recon = refine(&refine_request(*index, words, 1, 3, 1)).unwrap_err();
    assert!(recon.contains("reconstruction 3"), "{recon}");
    let flat = refine(&refine_request(*index, words, 1, 0, 2)).unwrap_err();
    assert!(flat.contains("flat refinement 2"), "{flat}");
}

#[test]
fn tables_are_the_crates_own() {
    let bytes = std::fs::read(conformance("valid/cornell-box.glb")).unwrap();
    let asset = Asset::open(conformance("valid/cornell-box.glb")).unwrap();
    let out = load(&load_request("cornell-box.glb", &bytes)).unwrap();
    let mut r = Reader::new(&out);
    assert_eq!(r.u32().unwrap(), 1, "GLB");
    r.string().unwrap();
    for _ in 0..r.u32().unwrap() {
        r.string().unwrap();
    }
    assert_eq!(r.u32().unwrap(), 1, "a camera");
    r.string().unwrap();
    for _ in 0..3 {
        r.floats().unwrap();
    }
    r.f32_bits().unwrap();
    r.u32().unwrap();
    r.f32_bits().unwrap();
    assert_eq!(r.u32().unwrap() as usize, asset.objects.len());
    for o in &asset.objects {
        assert_eq!(r.u32().unwrap(), o.index);
        // The object as `tables` reads it: the same words, then a reconstruction.
        let start = r.position();
        assert_eq!(r.string().unwrap(), o.object.name);
        // Kind, geometry hash and bit length.
        for _ in 0..5 {
            r.u32().unwrap();
        }
        r.floats().unwrap();
        for _ in 0..13 {
            r.words().unwrap();
        }
        let object_words = &out[start..r.position()];
        assert_eq!(r.u32().unwrap(), o.tree_depth);
        r.floats().unwrap();
        r.f32_bits().unwrap();
        for _ in 0..r.u32().unwrap() {
            r.u32().unwrap();
            r.string().unwrap();
            r.floats().unwrap();
        }
        let mut w = Writer::default();
        w.u32(o.index);
        let mut request = w.finish();
        request.extend_from_slice(object_words);
        // Smooth, adaptive.
        request.extend([0, 0]);
        let t = tables(&request).unwrap();
        let mut r = Reader::new(&t);
        assert_eq!(r.u32().unwrap(), o.tree_depth);
        for _ in 0..3 {
            r.u32().unwrap();
        }
        r.words().unwrap();
        r.u32().unwrap();
        r.u32().unwrap();
        for _ in 0..7 {
            r.words().unwrap();
        }
        if r.u32().unwrap() == 1 {
            let native = LoopKernelTables::new(&o.object.mesh).unwrap();
            assert_eq!(r.words().unwrap(), native.tri_flags);
            assert_eq!(r.words().unwrap(), native.crease);
            assert_eq!(r.words().unwrap(), native.weights);
            assert_eq!(r.u32().unwrap(), native.max_valence);
            assert_eq!(r.u32().unwrap(), native.ring_points);
        }
        let light = LightingTable::build_with(&o.object, Reconstruction::Smooth)
            .unwrap()
            .to_words()
            .unwrap();
        assert_eq!(r.words().unwrap(), light, "{}", o.object.name);
        let has_adaptive = r.u32().unwrap() == 1;
        assert_eq!(has_adaptive, o.object.kind == ObjectKind::Flat);
        if has_adaptive {
            let native = refine_adaptive_flat(&o.object).unwrap();
            let lists = native.kernel_lists();
            assert_eq!(r.u32().unwrap(), lists.vertices);
            assert_eq!(r.u32().unwrap(), lists.triangles);
            for section in &lists.sections {
                assert_eq!(&r.words().unwrap(), section);
            }
            assert_eq!(r.words().unwrap(), native.triangle_start);
        }
        // Asked for uniformly, a flat object has no adaptive lists.
        let n = request.len();
        request[n - 1] = 1;
        let t = tables(&request).unwrap();
        assert_eq!(*t.last().unwrap(), 0, "{}", o.object.name);
    }
}
