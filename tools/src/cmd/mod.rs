//! One module per `hce` subcommand.

pub mod inspect;
pub mod validate;
