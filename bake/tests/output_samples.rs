//! Baked glTF output on the three sample scenes and small hand-made ones: the extension is
//! embedded and linked as SPEC.md section 3 says, COLOR_0 carries the given colours, meshes are
//! de-instanced, and the result reads back with the `gltf` crate and hce-format.
//!
//! Set `HCE_KEEP_OUTPUT=DIR` to keep the baked samples (for the Khronos glTF-Validator).

use hce_bake::{bake_gltf, write_baked_gltf, ObjectLink, OutputError};
use hce_format::*;
use hce_format::{container_bytes, primitive_geometry, primitive_links, GltfAsset as Asset};
use hce_meshio::scene::{import_scene, ImportOptions, ImportedScene};
use std::path::{Path, PathBuf};

fn sample(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../samples")
        .join(name)
}

/// A valid container with one flat object per scene object whose control mesh is the
/// object's triangles unwelded (each an isolated component, so the adjacency tables are
/// trivial), one leaf tree and one colour per triangle.
fn container_for(scene: &ImportedScene) -> (Container, Vec<Option<ObjectLink>>) {
    let mut objects = Vec::new();
    for o in &scene.objects {
        let f = o.triangle_count();
        let corners: Vec<[f32; 3]> = o.indices.iter().map(|&i| o.positions[i as usize]).collect();
        let boundary_corner = VERTEX_BOUNDARY | (RULE_CORNER << VERTEX_RULE_SHIFT);
        let mut bits = BitWriter::new();
        let mut triangles = Vec::new();
        let mut normals = Vec::new();
        for t in 0..f {
            let bits_start = bits.push_tree(&[false]).unwrap() as u32;
            let [a, b, c] = [0, 1, 2].map(|k| corners[3 * t + k]);
            let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let n = [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ];
            let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            normals.push(if l > 0.0 {
                n.map(|x| x / l)
            } else {
                [0.0, 0.0, 1.0]
            });
            triangles.push(TriangleRecord {
                bits_start,
                colour_start: t as u32,
                normal_start: t as u32,
                normal_count: 1,
            });
        }
        let (bits, bit_len) = bits.finish();
        let v = 3 * f as u32;
        objects.push(Object {
            name: o.name.clone(),
            kind: ObjectKind::Flat,
            geometry_hash: o.geometry_hash(),
            mesh: ControlMesh {
                positions: corners.iter().flatten().copied().collect(),
                triangles: (0..v).collect(),
                ring_offsets: (0..=v).map(|i| 2 * i).collect(),
                ring: (0..v)
                    .flat_map(|i| {
                        let base = i - i % 3;
                        [base + (i + 1) % 3, base + (i + 2) % 3]
                    })
                    .collect(),
                vertex_flags: vec![boundary_corner; v as usize],
                spoke_flags: vec![SPOKE_SHARP | SPOKE_BOUNDARY; 2 * v as usize],
                corner_spokes: vec![0; v as usize],
                neighbours: vec![NO_NEIGHBOUR; v as usize],
                edges: (0..v).collect(),
            },
            triangles,
            normals,
            bits,
            bit_len,
            colours: (0..f)
                .map(|t| rgb9e5::encode([t as f32 / f as f32, 0.5, 0.25]))
                .collect(),
            corner_colours: Vec::new(),
        });
    }
    let links = (0..objects.len())
        .map(|i| {
            Some(ObjectLink {
                object: i as u32,
                first_triangle: 0,
            })
        })
        .collect();
    let c = Container {
        metadata: Metadata {
            generator: "hce-bake tests".into(),
            bake_parameters: "{}".into(),
            source_hash: scene.source_hash(),
        },
        objects,
    };
    let problems = validate(&c);
    assert!(problems.is_empty(), "{problems:?}");
    (c, links)
}

/// Object `i` gets the colour (i / 8, 0.5, 1.5) on every vertex (above 1 on purpose: linear
/// radiosity may exceed 1, and the writer must clamp it).
fn constant_colours(scene: &ImportedScene) -> Vec<Vec<[f32; 3]>> {
    scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| vec![[i as f32 / 8.0, 0.5, 1.5]; o.vertex_count()])
        .collect()
}

fn read_f32s(json: &serde_json::Value, bin: &[u8], accessor: usize) -> (usize, Vec<f32>) {
    let a = &json["accessors"][accessor];
    assert_eq!(a["componentType"], 5126);
    assert_eq!(a["type"], "VEC3");
    let count = a["count"].as_u64().unwrap() as usize;
    let view = &json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
    let off = view["byteOffset"].as_u64().unwrap_or(0) as usize
        + a["byteOffset"].as_u64().unwrap_or(0) as usize;
    let vals = bin[off..off + 12 * count]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    (count, vals)
}

/// Every check of the brief on one baked asset.
fn check_baked(
    scene: &ImportedScene,
    glb: &[u8],
    container: &Container,
    colours: &[Vec<[f32; 3]>],
) {
    check_baked_links(scene, glb, container, colours);
    let parsed = ::gltf::Gltf::from_slice(glb).expect("the gltf crate parses the output");
    // Nothing of the input is lost.
    let src = ::gltf::Gltf::open(&scene.path).unwrap();
    assert_eq!(parsed.nodes().len(), src.nodes().len());
    assert_eq!(parsed.materials().len(), src.materials().len());
    assert_eq!(parsed.cameras().len(), src.cameras().len());
    assert_eq!(
        parsed.lights().map_or(0, |l| l.len()),
        src.lights().map_or(0, |l| l.len())
    );
}

/// The output's extension, container, links and `COLOR_0`, against what was baked.
fn check_baked_links(
    scene: &ImportedScene,
    glb: &[u8],
    container: &Container,
    colours: &[Vec<[f32; 3]>],
) {
    ::gltf::Gltf::from_slice(glb).expect("the gltf crate parses the output");
    let asset = Asset::parse(glb).unwrap();
    let json = &asset.json;
    let used: Vec<&str> = json["extensionsUsed"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(used.contains(&"EXT_hce_baked_lighting"));
    let required = json.get("extensionsRequired").and_then(|r| r.as_array());
    assert!(required.is_none_or(|r| !r.iter().any(|e| e == "EXT_hce_baked_lighting")));
    let buffers = asset
        .buffers(|_| Err("no external buffers".into()))
        .unwrap();
    let view = hce_format::root_link(json).unwrap().unwrap().buffer_view;
    assert_eq!(
        json["bufferViews"][view]["byteOffset"].as_u64().unwrap() % 256,
        0
    );
    let bytes = container_bytes(json, &buffers).unwrap().unwrap();
    assert_eq!(bytes, write(container).unwrap().as_slice());
    assert_eq!(&read(bytes).unwrap(), container);
    let links = primitive_links(json).unwrap();
    assert_eq!(links.len(), scene.objects.len());
    for (i, link) in links.iter().enumerate() {
        // Links come out in mesh order; find the object by its container index.
        let o = &scene.objects[link.object as usize];
        let (hash, tris) = primitive_geometry(json, &buffers, link.mesh, link.primitive).unwrap();
        assert_eq!(hash, link.geometry_hash, "link {i}");
        assert_eq!(hash, container.objects[link.object as usize].geometry_hash);
        assert_eq!(tris, o.triangle_count());
        let prim = &json["meshes"][link.mesh]["primitives"][link.primitive];
        let pos = prim["attributes"]["POSITION"].as_u64().unwrap() as usize;
        let col = prim["attributes"]["COLOR_0"].as_u64().unwrap() as usize;
        let (n, _) = read_f32s(json, &buffers[0], pos);
        let (m, values) = read_f32s(json, &buffers[0], col);
        assert_eq!(n, m);
        assert_eq!(m, o.vertex_count());
        // COLOR_0 is clamped to [0, 1], as glTF requires.
        let want: Vec<f32> = colours[link.object as usize]
            .iter()
            .flatten()
            .map(|x| x.clamp(0.0, 1.0))
            .collect();
        assert_eq!(values, want);
        assert!(values.iter().all(|&v| (0.0..=1.0).contains(&v)));
    }
}

fn keep(name: &str, bytes: &[u8]) {
    if let Some(dir) = std::env::var_os("HCE_KEEP_OUTPUT") {
        std::fs::write(Path::new(&dir).join(name), bytes).unwrap();
    }
}

#[test]
fn samples_bake_to_valid_extended_glbs() {
    for name in ["teatime.glb", "chesstime.glb", "cornell-box.glb"] {
        let scene = import_scene(&sample(name), &ImportOptions::default()).unwrap();
        let (c, links) = container_for(&scene);
        let colours = constant_colours(&scene);
        let glb = write_baked_gltf(&scene, &colours, &write(&c).unwrap(), &links).unwrap();
        check_baked(&scene, &glb, &c, &colours);
        // Deterministic: the same inputs give the same bytes.
        let again = write_baked_gltf(&scene, &colours, &write(&c).unwrap(), &links).unwrap();
        assert_eq!(glb, again);
        // The output imports again with the same geometry.
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("baked.glb");
        std::fs::write(&out, &glb).unwrap();
        let back = import_scene(&out, &ImportOptions::default()).unwrap();
        assert_eq!(back.triangle_count(), scene.triangle_count());
        let multires: Vec<bool> = back.objects.iter().map(|o| o.multires).collect();
        assert_eq!(
            multires,
            scene.objects.iter().map(|o| o.multires).collect::<Vec<_>>()
        );
        keep(&name.replace(".glb", ".baked.glb"), &glb);
    }
}

#[test]
fn gltf_output_writes_json_and_bin_atomically() {
    let scene = import_scene(&sample("cornell-box.glb"), &ImportOptions::default()).unwrap();
    let (c, links) = container_for(&scene);
    let colours = constant_colours(&scene);
    let baked = bake_gltf(&scene, &colours, &write(&c).unwrap(), &links).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cornell baked.gltf");
    baked.write(&path).unwrap();
    let bin = std::fs::read(dir.path().join("cornell baked.bin")).unwrap();
    assert_eq!(bin, baked.bin);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("cornell%20baked.bin"));
    // No temporary file is left behind.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
    let back = import_scene(&path, &ImportOptions::default()).unwrap();
    assert_eq!(back.triangle_count(), 32);
    if let Some(keep_dir) = std::env::var_os("HCE_KEEP_OUTPUT") {
        baked
            .write(&Path::new(&keep_dir).join("cornell-box.baked.gltf"))
            .unwrap();
    }
    let e = baked.write(&dir.path().join("x.obj")).unwrap_err();
    assert!(matches!(e, OutputError::OutputExtension { .. }), "{e}");
}

#[test]
fn bad_inputs_are_errors_naming_the_object() {
    let scene = import_scene(&sample("cornell-box.glb"), &ImportOptions::default()).unwrap();
    let (c, mut links) = container_for(&scene);
    let bytes = write(&c).unwrap();
    let mut colours = constant_colours(&scene);
    colours[2].pop();
    let e = write_baked_gltf(&scene, &colours, &bytes, &links).unwrap_err();
    assert!(
        e.to_string().contains("back_wall") && e.to_string().contains("colours for"),
        "{e}"
    );
    let colours = constant_colours(&scene);
    links[1] = Some(ObjectLink {
        object: 99,
        first_triangle: 0,
    });
    let e = write_baked_gltf(&scene, &colours, &bytes, &links).unwrap_err();
    assert!(e.to_string().contains("container object 99"), "{e}");
    links[1] = Some(ObjectLink {
        object: 1,
        first_triangle: 1,
    });
    let e = write_baked_gltf(&scene, &colours, &bytes, &links).unwrap_err();
    assert!(e.to_string().contains("exceed"), "{e}");
    // Two objects of different meshes may not share one container object.
    links[1] = Some(ObjectLink {
        object: 0,
        first_triangle: 0,
    });
    let e = write_baked_gltf(&scene, &colours, &bytes, &links).unwrap_err();
    assert!(e.to_string().contains("one mesh"), "{e}");
    links[1] = None;
    let e = write_baked_gltf(&scene, &colours, &bytes[..100], &links).unwrap_err();
    assert!(matches!(e, OutputError::Container(_)), "{e}");
}

const INSTANCED: &str = r#"{
 "asset": {"version": "2.0"},
 "scene": 0,
 "scenes": [{"nodes": [0, 1]}],
 "nodes": [{"name": "a", "mesh": 0}, {"name": "b", "mesh": 0, "translation": [2, 0, 0]}],
 "materials": [{"emissiveFactor": [1, 1, 1]}],
 "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
 "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
 "bufferViews": [{"buffer": 0, "byteLength": 36, "target": 34962}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}]
}"#;

#[test]
fn shared_meshes_are_deinstanced_with_their_own_colours() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("instanced.gltf");
    std::fs::write(&path, INSTANCED).unwrap();
    let scene = import_scene(&path, &ImportOptions::default()).unwrap();
    assert_eq!(scene.objects.len(), 2);
    assert_eq!(scene.objects[1].world_positions[1], [3.0, 0.0, 0.0]);
    let (c, links) = container_for(&scene);
    let colours = constant_colours(&scene);
    let glb = write_baked_gltf(&scene, &colours, &write(&c).unwrap(), &links).unwrap();
    let asset = Asset::parse(&glb).unwrap();
    assert_eq!(asset.json["meshes"].as_array().unwrap().len(), 2);
    assert_eq!(asset.json["nodes"][1]["mesh"], 1);
    let links = primitive_links(&asset.json).unwrap();
    assert_eq!((links[0].mesh, links[0].object), (0, 0));
    assert_eq!((links[1].mesh, links[1].object), (1, 1));
    let c0 = &asset.json["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"];
    let c1 = &asset.json["meshes"][1]["primitives"][0]["attributes"]["COLOR_0"];
    assert_ne!(c0, c1);
    // The data: URI buffer was merged into the BIN chunk.
    assert!(asset.json["buffers"][0].get("uri").is_none());
    check_baked(&scene, &glb, &c, &colours);
    keep("instanced.baked.glb", &glb);
}

/// The scene above as gltf-transform's `instance` writes it: one node, its mesh drawn twice by
/// EXT_mesh_gpu_instancing (here required, which the extension allows).
const GPU_INSTANCED: &str = r#"{
 "asset": {"version": "2.0"},
 "extensionsUsed": ["EXT_mesh_gpu_instancing"],
 "extensionsRequired": ["EXT_mesh_gpu_instancing"],
 "scenes": [{"nodes": [0]}],
 "nodes": [{"name": "tris", "mesh": 0,
            "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 1}}}}],
 "materials": [{"emissiveFactor": [1, 1, 1]}],
 "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
 "buffers": [{"byteLength": 60, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAAAAAAAAQAAAAAAAAAAA"}],
 "bufferViews": [{"buffer": 0, "byteLength": 36, "target": 34962},
                 {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
               {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC3"}]
}"#;

#[test]
fn gpu_instances_are_baked_one_object_each_in_nodes_of_their_own() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("gpu-instanced.gltf");
    std::fs::write(&path, GPU_INSTANCED).unwrap();
    let scene = import_scene(&path, &ImportOptions::default()).unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .all(|w| !w.contains("EXT_mesh_gpu_instancing")),
        "{:?}",
        scene.warnings
    );
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["tris#0", "tris#1"]);
    assert_eq!(scene.objects[0].world_positions[1], [1.0, 0.0, 0.0]);
    assert_eq!(scene.objects[1].world_positions[1], [3.0, 0.0, 0.0]);
    let (c, links) = container_for(&scene);
    let colours = constant_colours(&scene);
    let glb = write_baked_gltf(&scene, &colours, &write(&c).unwrap(), &links).unwrap();
    let asset = Asset::parse(&glb).unwrap();
    let j = &asset.json;
    assert!(!j.to_string().contains("EXT_mesh_gpu_instancing"), "{j}");
    assert_eq!(j["nodes"][0]["children"], serde_json::json!([1, 2]));
    assert_eq!(
        (&j["nodes"][1]["mesh"], &j["nodes"][2]["mesh"]),
        (&0.into(), &1.into())
    );
    assert_eq!(
        j["nodes"][2]["translation"],
        serde_json::json!([2.0, 0.0, 0.0])
    );
    let links = primitive_links(j).unwrap();
    assert_eq!((links[0].mesh, links[0].object), (0, 0));
    assert_eq!((links[1].mesh, links[1].object), (1, 1));
    // The node the instances were (the `gltf` crate cannot read the source, which requires
    // the extension) and each instance a node.
    assert_eq!(j["nodes"].as_array().unwrap().len(), 3);
    check_baked_links(&scene, &glb, &c, &colours);
}

#[test]
fn obj_scenes_become_gltf_with_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("s.mtl"),
        "newmtl lamp\nKd 0 0 0\nKe 5 4 3\nnewmtl wall\nKd 0.5 0.6 0.7\n",
    )
    .unwrap();
    let obj = dir.path().join("s.obj");
    std::fs::write(
        &obj,
        "mtllib s.mtl\no lamp\nv 0 2 0\nv 1 2 0\nv 0 2 1\nvn 0 -3 0\nusemtl lamp\nf 1//1 3//1 2//1\n\
         o wall\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl wall\nf 4 5 6 7\n",
    )
    .unwrap();
    let scene = import_scene(
        &obj,
        &ImportOptions {
            multires: vec!["wall".into()],
        },
    )
    .unwrap();
    let (c, links) = container_for(&scene);
    let colours = constant_colours(&scene);
    let glb = write_baked_gltf(&scene, &colours, &write(&c).unwrap(), &links).unwrap();
    let asset = Asset::parse(&glb).unwrap();
    let j = &asset.json;
    assert_eq!(j["nodes"][1]["name"], "wall");
    assert_eq!(j["nodes"][1]["extras"]["hce"]["multires"], true);
    // Emission 5 is written as a unit factor times the strength.
    let m = &j["materials"][0];
    assert_eq!(
        m["emissiveFactor"],
        serde_json::json!([1.0f32, 0.8f32, 0.6f32])
    );
    assert_eq!(
        m["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"],
        5.0
    );
    let buffers = asset.buffers(|_| Err("none".into())).unwrap();
    for l in primitive_links(j).unwrap() {
        let (hash, _) = primitive_geometry(j, &buffers, l.mesh, l.primitive).unwrap();
        assert_eq!(hash, scene.objects[l.object as usize].geometry_hash());
    }
    // The normal (0, -3, 0) was normalised.
    let out = dir.path().join("s.glb");
    std::fs::write(&out, &glb).unwrap();
    let back = import_scene(&out, &ImportOptions::default()).unwrap();
    assert_eq!(
        back.objects[0].normals.as_ref().unwrap()[0],
        [0.0, -1.0, 0.0]
    );
    assert_eq!(back.material_of(&back.objects[0]).emission, [5.0, 4.0, 3.0]);
    assert!(back.objects[1].multires);
    keep("obj.baked.glb", &glb);
}

#[test]
fn rebaking_a_baked_file_replaces_the_extension() {
    let scene = import_scene(&sample("cornell-box.glb"), &ImportOptions::default()).unwrap();
    let (c, links) = container_for(&scene);
    let colours = constant_colours(&scene);
    let glb = write_baked_gltf(&scene, &colours, &write(&c).unwrap(), &links).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("once.glb");
    std::fs::write(&first, &glb).unwrap();
    let scene2 = import_scene(&first, &ImportOptions::default()).unwrap();
    assert!(scene2
        .warnings
        .iter()
        .any(|w| w.contains("already carries baked lighting")));
    let (c2, links2) = container_for(&scene2);
    let colours2: Vec<Vec<[f32; 3]>> = colours
        .iter()
        .map(|v| vec![[0.1, 0.2, 0.3]; v.len()])
        .collect();
    let glb2 = write_baked_gltf(&scene2, &colours2, &write(&c2).unwrap(), &links2).unwrap();
    let asset = Asset::parse(&glb2).unwrap();
    let used = asset.json["extensionsUsed"].as_array().unwrap();
    assert_eq!(
        used.iter()
            .filter(|e| *e == "EXT_hce_baked_lighting")
            .count(),
        1
    );
    check_baked(&scene2, &glb2, &c2, &colours2);
    keep("rebaked.glb", &glb2);
}

#[test]
fn primitives_sharing_an_object_must_not_overlap() {
    let scene = import_scene(&sample("chesstime.glb"), &ImportOptions::default()).unwrap();
    let board: Vec<usize> = (0..scene.objects.len())
        .filter(|&i| scene.objects[i].node_name.as_deref() == Some("board"))
        .collect();
    assert!(
        board.len() > 1,
        "the board has one primitive per rank and colour"
    );
    let (c, mut links) = container_for(&scene);
    let shared = links[board[0]];
    links[board[1]] = shared;
    let e = write_baked_gltf(
        &scene,
        &constant_colours(&scene),
        &write(&c).unwrap(),
        &links,
    )
    .unwrap_err();
    assert!(e.to_string().contains("overlap"), "{e}");
}
