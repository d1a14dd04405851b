//! Rewrites `conformance/` (files and `manifest.json`) from the examples, the bundled Cornell
//! box and their mutations: `cargo run -p hce-tests --bin gen-conformance [-- --keep-baked]`.
#![forbid(unsafe_code)]

use std::path::Path;

fn main() -> std::io::Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scratch = tempfile::tempdir()?;
    // `--keep-baked`: the committed baked file as it is, when only rules or cases changed (its
    // bytes follow the baker, so baking again also rewrites it and its expectations).
    let kept = root.join("conformance/valid/cornell-box.glb");
    let cornell = if std::env::args().any(|a| a == "--keep-baked") {
        std::fs::read(&kept)?
    } else {
        hce_tests::conformance::bake_cornell(&root.join("samples"), scratch.path())
    };
    let dir = root.join("conformance");
    let mut cases = hce_tests::conformance::cases(cornell);
    // Written by glTF Transform, not here: read as committed (`TOOL_CASES` says how to remake them).
    cases.extend(hce_tests::conformance::tool_cases(|f| {
        std::fs::read(dir.join(f))
    })?);
    hce_tests::conformance::generate(&dir, &cases)?;
    println!(
        "wrote {} cases and manifest.json to {}",
        cases.len(),
        dir.display()
    );
    Ok(())
}
