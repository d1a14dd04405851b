//! Fuzz target: any bytes through `hce_fuzz::load_mesh` (see fuzz/src/lib.rs, which
//! `bake/tests/fuzz_bodies.rs` also runs on stable). Nothing may panic, hang or allocate beyond
//! what the input justifies.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| hce_fuzz::load_mesh(data));
