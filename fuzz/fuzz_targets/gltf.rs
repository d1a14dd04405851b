//! Fuzz target: any bytes as a GLB or .gltf through the EXT_hce_baked_lighting helpers (asset
//! parsing, buffer loading, container extraction, links and geometry hashes). Nothing may panic
//! or allocate beyond what the input justifies.
#![no_main]

use hce_format::{container_bytes, linked_geometries, primitive_links, GltfAsset as Asset};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(asset) = Asset::parse(data) else {
        return;
    };
    let Ok(buffers) = asset.buffers(|_| Err("external files are not followed".into())) else {
        return;
    };
    if let Ok(Some(bytes)) = container_bytes(&asset.json, &buffers) {
        let _ = hce_format::validate_bytes(bytes);
    }
    if let Ok(links) = primitive_links(&asset.json) {
        let _ = linked_geometries(&asset.json, &buffers, &links);
    }
});
