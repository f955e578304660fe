//! The subcommands of `radlab`.

pub mod catalogue;
pub mod compare;
pub mod export;
pub mod probe;
pub mod render;
pub mod solve;
