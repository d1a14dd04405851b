//! Fuzz target: any bytes as a GLB or .gltf through the EXT_hce_baked_lighting helpers (asset
//! parsing, buffer loading, container extraction, links and geometry hashes), the accessor
//! reader (strides, sparse, quantized types, EXT_meshopt_compression decoding) on every
//! accessor, and the whole validator, whose link check runs the same-geometry rule (SPEC.md
//! 2.6) against the container. Nothing may panic or allocate beyond what the input justifies.
#![no_main]

use hce_format::{
    container_bytes, linked_geometries, primitive_links, read_accessor, validate_asset_report,
    GltfAsset as Asset,
};
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
    let accessors = asset
        .json
        .get("accessors")
        .and_then(|a| a.as_array())
        .map_or(0, Vec::len);
    for i in 0..accessors.min(64) {
        let _ = read_accessor(&asset.json, &buffers, i);
    }
    let _ = validate_asset_report(&asset.json, &buffers);
});
