//! Fuzz target: any bytes through the container reader and validator. Neither may panic, hang
//! or allocate beyond a small multiple of the input; whatever reads must write back and read
//! to the same bytes.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let read = hce_format::read(data);
    let problems = hce_format::validate_bytes(data);
    if problems.is_empty() {
        assert!(read.is_ok(), "valid per validator but unreadable: {read:?}");
    }
    if let Ok(c) = read {
        let bytes = hce_format::write(&c).expect("a read container is writable");
        let again = hce_format::read(&bytes).expect("rewritten file reads");
        assert_eq!(hce_format::write(&again).unwrap(), bytes);
    }
});
