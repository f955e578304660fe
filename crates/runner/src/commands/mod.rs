//! The subcommands of `radlab`.

pub mod catalogue;
pub mod probe;
pub mod render;
pub mod solve;
