//! `hce subdivide` on a glTF scene places every mesh instance where its node puts it.

mod common;

#[test]
fn gltf_node_transforms_are_applied() {
    let dir = tempfile::tempdir().unwrap();
    // One triangle, used by a node that translates by (10, 0, 0) and scales by 2 (its parent
    // translates, the node scales).
    let mut bin = Vec::new();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        bin.extend(p.iter().flat_map(|c| c.to_le_bytes()));
    }
    std::fs::write(dir.path().join("tri.bin"), &bin).unwrap();
    let json = r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],
        "nodes":[{"translation":[10,0,0],"children":[1]},{"scale":[2,2,2],"mesh":0}],
        "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
        "buffers":[{"byteLength":36,"uri":"tri.bin"}],
        "bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36}],
        "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}"#;
    let input = dir.path().join("scene.gltf");
    std::fs::write(&input, json).unwrap();
    let output = dir.path().join("out.obj");
    let out = common::command()
        .args(["subdivide", input.to_str().unwrap(), "--level", "1", "-o"])
        .arg(&output)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&output).unwrap();
    let points: Vec<[f32; 3]> = text
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let v: Vec<f32> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    // A lone triangle keeps its corners (boundary corners) and gains its edge midpoints.
    let mut want = vec![
        [10.0, 0.0, 0.0],
        [12.0, 0.0, 0.0],
        [10.0, 2.0, 0.0],
        [11.0, 0.0, 0.0],
        [11.0, 1.0, 0.0],
        [10.0, 1.0, 0.0],
    ];
    let mut got = points.clone();
    let key = |p: &[f32; 3]| p.map(f32::to_bits);
    want.sort_by_key(key);
    got.sort_by_key(key);
    assert_eq!(got, want, "{text}");
}
