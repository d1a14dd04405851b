//! A stable, deterministic stand-in for the scene and mesh reader fuzz targets: the bodies in
//! `fuzz/src/lib.rs` (included here as a module, so they are compile-checked on stable) run
//! over inputs mutated from small valid scenes by a seeded PRNG, with a bound on the memory any
//! one input may make them allocate. Crash inputs found by cargo-fuzz are kept, one file per
//! bug, in `tests/regressions/<target>/` and replayed by `regressions_still_pass`.
//!
//! `HCE_MUTATIONS=N` runs N inputs per target instead of the default 300.

#[path = "../../fuzz/src/lib.rs"]
mod bodies;

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

struct Counting;
static CURRENT: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator unchanged; it only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now = CURRENT.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
        PEAK.fetch_max(now, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        CURRENT.fetch_sub(layout.size(), Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Tests run one at a time so that the peak belongs to one input.
static SERIAL: Mutex<()> = Mutex::new(());

/// Most bytes one input may make a body hold at once beyond what was live before it.
const ALLOCATION_BOUND: usize = 256 << 20;

/// The last panic, even one a reader caught (the glTF importer catches the `gltf` crate's
/// panics and reports an error): libFuzzer counts those as crashes, and so does this test.
static PANICKED: Mutex<Option<String>> = Mutex::new(None);

/// Runs `body` on `input` and checks that nothing panicked and its allocation peak.
fn run(name: &str, body: fn(&[u8]), input: &[u8]) {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        std::panic::set_hook(Box::new(|info| {
            if let Ok(mut p) = PANICKED.lock() {
                *p = Some(info.to_string());
            }
        }))
    });
    let before = CURRENT.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    body(input);
    if let Some(p) = PANICKED.lock().unwrap_or_else(|e| e.into_inner()).take() {
        panic!("{name}: a {}-byte input panicked: {p}", input.len());
    }
    let peak = PEAK.load(Ordering::Relaxed) - before;
    assert!(
        peak <= ALLOCATION_BOUND,
        "{name}: a {}-byte input made the reader allocate {peak} bytes",
        input.len()
    );
}

/// xorshift64*: small, seeded, the same on every machine.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Values that tend to sit on the edge of a check.
const TOKENS: &[&str] = &[
    "0",
    "-1",
    "1",
    "3",
    "255",
    "65536",
    "4294967295",
    "4294967296",
    "2147483648",
    "1e30",
    "-1e30",
    "nan",
    "inf",
    "0.0",
    "-0",
    "999999999999",
    "\"\"",
    "[]",
    "{}",
    "null",
    "f 1 2 3",
    "f -1 -2 -3",
    "f 1/1/1 2/2/2 3/3/3 4/4/4",
    "v 1e38 1e38 1e38",
    "l 1 2",
    "p 1",
    "mtllib x.mtl",
    "usemtl m",
    "Ke 1 1 1",
];

/// A text-aware mutation: flips, replacements of a number by an edge value, token inserts,
/// deletions and duplications of ranges.
fn mutate(rng: &mut Rng, seed: &[u8]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(3) {
        if b.is_empty() {
            b.push(b'0');
        }
        match rng.below(6) {
            0 => {
                let at = rng.below(b.len());
                b[at] ^= 1 << rng.below(8);
            }
            1 => {
                // Replace the run of digits around a random digit by a token.
                let digits: Vec<usize> = (0..b.len()).filter(|&i| b[i].is_ascii_digit()).collect();
                if let Some(&at) = digits.get(rng.below(digits.len())) {
                    let (mut s, mut e) = (at, at);
                    while s > 0 && b[s - 1].is_ascii_digit() {
                        s -= 1;
                    }
                    while e < b.len() && b[e].is_ascii_digit() {
                        e += 1;
                    }
                    let t = TOKENS[rng.below(TOKENS.len())].as_bytes();
                    b.splice(s..e, t.iter().copied());
                }
            }
            2 => {
                let at = rng.below(b.len() + 1);
                let t = TOKENS[rng.below(TOKENS.len())];
                let line = format!("\n{t}\n");
                b.splice(at..at, line.bytes());
            }
            3 => {
                let at = rng.below(b.len());
                let len = 1 + rng.below(16.min(b.len() - at));
                b.drain(at..at + len);
            }
            4 => {
                let at = rng.below(b.len());
                let len = 1 + rng.below(64.min(b.len() - at));
                let copy: Vec<u8> = b[at..at + len].to_vec();
                let to = rng.below(b.len() + 1);
                b.splice(to..to, copy);
            }
            _ => {
                let at = rng.below(b.len());
                b.truncate(at.max(1));
            }
        }
    }
    b
}

/// A GLB from JSON text and a BIN chunk (the text need not be valid JSON).
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |n: usize| n.div_ceil(4) * 4;
    let (jl, bl) = (pad(json.len()), pad(bin.len()));
    let total = 12 + 8 + jl + if bin.is_empty() { 0 } else { 8 + bl };
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((jl as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.resize(20 + jl, b' ');
    if !bin.is_empty() {
        out.extend((bl as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
        out.resize(total, 0);
    }
    out
}

fn sample(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../samples")
            .join(name),
    )
    .unwrap()
}

/// A lit quad as `.gltf` JSON with its buffer in a data URI.
fn quad_gltf() -> String {
    let mut bin = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    bin.extend([0u8, 1, 2, 0, 2, 3]);
    quad_gltf_with(&bin)
}

/// [`quad_gltf`] drawn twice by EXT_mesh_gpu_instancing (required), so that mutations reach the
/// instance expansion: translations and quaternion rotations in accessors 2 and 3.
fn quad_instanced_gltf() -> String {
    let mut bin = Vec::new();
    for p in [[0f32, 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]] {
        bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    bin.extend([0u8, 1, 2, 0, 2, 3, 0, 0]);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    for x in [0f32, 0., 0., 3., 0., 0., 0., 0., 0., 1., 0., 0., h, h] {
        bin.extend(x.to_le_bytes());
    }
    let mut j: serde_json::Value = serde_json::from_str(&quad_gltf_with(&bin)).unwrap();
    j["extensionsUsed"]
        .as_array_mut()
        .unwrap()
        .push("EXT_mesh_gpu_instancing".into());
    j["extensionsRequired"] = serde_json::json!(["EXT_mesh_gpu_instancing"]);
    j["bufferViews"].as_array_mut().unwrap().extend([
        serde_json::json!({"buffer": 0, "byteOffset": 56, "byteLength": 24}),
        serde_json::json!({"buffer": 0, "byteOffset": 80, "byteLength": 32}),
    ]);
    j["accessors"].as_array_mut().unwrap().extend([
        serde_json::json!({"bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3"}),
        serde_json::json!({"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC4"}),
    ]);
    j["nodes"][0]["extensions"] = serde_json::json!({"EXT_mesh_gpu_instancing":
        {"attributes": {"TRANSLATION": 2, "ROTATION": 3}}});
    j.to_string()
}

fn quad_gltf_with(bin: &[u8]) -> String {
    let uri = format!("data:application/octet-stream;base64,{}", base64(bin));
    format!(
        r#"{{"asset": {{"version": "2.0"}},
 "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_emissive_strength"],
 "extensions": {{"KHR_lights_punctual": {{"lights": [{{"type": "point", "intensity": 5, "range": 10}}]}}}},
 "scene": 0, "scenes": [{{"nodes": [0, 1]}}],
 "nodes": [{{"name": "quad", "mesh": 0, "scale": [2, 2, 2], "extras": {{"hce": {{"multires": true}}}}}},
           {{"translation": [0, 0, 3], "extensions": {{"KHR_lights_punctual": {{"light": 0}}}}}}],
 "materials": [{{"emissiveFactor": [1, 0.5, 0], "extensions": {{"KHR_materials_emissive_strength": {{"emissiveStrength": 4}}}}}}],
 "meshes": [{{"name": "m", "primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
 "buffers": [{{"byteLength": {len}, "uri": "{uri}"}}],
 "bufferViews": [{{"buffer": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 6}}],
 "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
               {{"bufferView": 1, "componentType": 5121, "count": 6, "type": "SCALAR"}}]}}"#,
        len = bin.len()
    )
}

fn base64(b: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in b.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[(n >> (18 - 6 * k)) as usize & 63] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

const OBJ: &str = "mtllib scene.mtl\n\
o floor\nv 0 0 0\nv 2 0 0\nv 2 0 2\nv 0 0 2\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 1 0\n\
usemtl white\nf 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1\n\
o lamp\nv 0.5 1 0.5\nv 1.5 1 0.5\nv 1.5 1 1.5\nv 0.5 1 1.5\nusemtl lamp\nf 5 6 7 8\n\
g wire\nl 1 5\np 2\n";
const MTL: &str = "newmtl white\nKd 0.8 0.7 0.6\nnewmtl lamp\nKd 0 0 0\nKe 4 4 3\n";

/// A fuzz target: its name, its body and its seeds (already in the target's input layout).
type Target = (&'static str, fn(&[u8]), Vec<Vec<u8>>);

fn seeds() -> Vec<Target> {
    let cornell = sample("cornell-box.glb");
    let asset = hce_format::GltfAsset::parse(&cornell).unwrap();
    let cornell_json = serde_json::to_vec(&asset.json).unwrap();
    let cornell_bin = asset.bin.clone().unwrap();
    let obj_mtl = [OBJ.as_bytes(), &[0], MTL.as_bytes()].concat();
    let gltf = quad_gltf().into_bytes();
    let instanced = quad_instanced_gltf().into_bytes();
    vec![
        (
            "import_gltf",
            bodies::import_gltf as fn(&[u8]),
            vec![cornell.clone(), gltf.clone(), instanced],
        ),
        (
            "import_obj",
            bodies::import_obj,
            vec![obj_mtl, OBJ.as_bytes().to_vec()],
        ),
        (
            "load_mesh",
            bodies::load_mesh,
            vec![
                [&[0u8][..], OBJ.as_bytes()].concat(),
                [&[1u8][..], &gltf].concat(),
                [&[2u8][..], &glb(&cornell_json, &cornell_bin)].concat(),
            ],
        ),
    ]
}

#[test]
fn seeds_are_accepted_and_mutations_never_panic() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    // The seeds themselves import: the mutations start from inputs that reach deep.
    let cornell = sample("cornell-box.glb");
    let s = hce_meshio::scene::import_scene_bytes(
        hce_meshio::scene::SceneBytes::Gltf(&cornell),
        &Default::default(),
    )
    .unwrap();
    assert_eq!(s.objects.len(), 8);
    let s = hce_meshio::scene::import_scene_bytes(
        hce_meshio::scene::SceneBytes::Gltf(quad_gltf().as_bytes()),
        &Default::default(),
    )
    .unwrap();
    assert_eq!((s.objects.len(), s.lights.len()), (1, 1));
    assert!(s.objects[0].multires, "node extras select multiresolution");
    assert_eq!(s.materials[0].emission, [4.0, 2.0, 0.0]);
    let s = hce_meshio::scene::import_scene_bytes(
        hce_meshio::scene::SceneBytes::Gltf(quad_instanced_gltf().as_bytes()),
        &Default::default(),
    )
    .unwrap();
    // Two instances: the second turned a quarter about z and moved 3 along x, then scaled by
    // the node's 2, so corner (1, 0, 0) lands at (6, 2, 0).
    assert_eq!(s.objects.len(), 2);
    let far = s.objects[1].world_positions[1];
    assert!(
        (far[0] - 6.0).abs() < 1e-5 && (far[1] - 2.0).abs() < 1e-5,
        "{far:?}"
    );
    let s = hce_meshio::scene::import_scene_bytes(
        hce_meshio::scene::SceneBytes::Obj {
            obj: OBJ.as_bytes(),
            mtl: Some(MTL.as_bytes()),
        },
        &Default::default(),
    )
    .unwrap();
    assert_eq!(s.objects.len(), 2);
    assert!(
        s.warnings.iter().any(|w| w.contains("1 point and 1 line")),
        "{:?}",
        s.warnings
    );
    let lamp = s.objects.iter().find(|o| o.name == "lamp").unwrap();
    assert_eq!(s.material_of(lamp).emission, [4.0, 4.0, 3.0]);

    let runs: usize = std::env::var("HCE_MUTATIONS")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(300);
    let mut rng = Rng(0x243f_6a88_85a3_08d3);
    for (name, body, seeds) in seeds() {
        for s in &seeds {
            run(name, body, s);
        }
        for _ in 0..runs {
            let seed = &seeds[rng.below(seeds.len())];
            let input = if name == "import_gltf" && seed.starts_with(b"glTF") {
                // Mutate the JSON chunk of a GLB and wrap it again, so that the damage gets
                // past the container and into the glTF.
                let asset = hce_format::GltfAsset::parse(seed).unwrap();
                let json = serde_json::to_vec(&asset.json).unwrap();
                glb(
                    &mutate(&mut rng, &json),
                    asset.bin.as_deref().unwrap_or(&[]),
                )
            } else {
                mutate(&mut rng, seed)
            };
            run(name, body, &input);
        }
    }
}

#[test]
fn regressions_still_pass() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/regressions");
    let mut replayed = 0;
    for (name, body, _) in seeds() {
        let Ok(entries) = std::fs::read_dir(dir.join(name)) else {
            continue;
        };
        let mut files: Vec<_> = entries.flatten().map(|e| e.path()).collect();
        files.sort();
        for f in files {
            let input = std::fs::read(&f).unwrap();
            run(name, body, &input);
            replayed += 1;
        }
    }
    println!("replayed {replayed} regression inputs");
    assert!(
        replayed >= 1,
        "no regression input found under {}",
        dir.display()
    );
    // The first bug: tobj 4.0 panics on a colour line with two values; it is now a warning.
    let bug = std::fs::read(dir.join("import_obj/tobj-colour-with-two-values.bin")).unwrap();
    let (obj, mtl) = bug.split_at(bug.iter().position(|&b| b == 0).unwrap());
    let s = hce_meshio::scene::import_scene_bytes(
        hce_meshio::scene::SceneBytes::Obj {
            obj,
            mtl: Some(&mtl[1..]),
        },
        &Default::default(),
    )
    .unwrap();
    assert!(
        s.warnings.iter().any(|w| w.contains("needs three values")),
        "{:?}",
        s.warnings
    );
    assert_eq!(s.material_of(&s.objects[0]).emission, [1.0; 3]);
}
