//! Rewrites `conformance/` (files and `manifest.json`) from the examples, the bundled Cornell
//! box and their mutations: `cargo run -p hce-tests --bin gen-conformance`.
#![forbid(unsafe_code)]

use std::path::Path;

fn main() -> std::io::Result<()> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scratch = tempfile::tempdir()?;
    let cornell = hce_tests::conformance::bake_cornell(&root.join("samples"), scratch.path());
    let cases = hce_tests::conformance::cases(cornell);
    let dir = root.join("conformance");
    hce_tests::conformance::generate(&dir, &cases)?;
    println!(
        "wrote {} cases and manifest.json to {}",
        cases.len(),
        dir.display()
    );
    Ok(())
}
