//! End-to-end tests of the hce toolchain live in `tests/tests/`; this library holds their shared
//! helpers and the conformance suite's generator ([`conformance`]).
#![forbid(unsafe_code)]

pub mod conformance;
