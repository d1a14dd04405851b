//! # hce-bake
//!
//! The baker: normal sets (stage 1), enriched hierarchical radiosity (stage 2) and HCE encoding.

pub mod import;
pub mod output;
