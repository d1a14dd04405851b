//! End-to-end tests of the hce toolchain live in `tests/tests/`; this library holds their shared
//! helpers.
