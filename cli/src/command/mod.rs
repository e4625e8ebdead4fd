//! What `svi` does: each subcommand's work, called by the binary's dispatch.

pub mod bench;
pub mod bench_spectral;
pub mod compare;
pub mod ensemble;
pub mod field;
pub mod list;
pub mod molly;
pub mod peers;
pub mod run;
pub mod scale;
pub mod space;
pub mod spectral;
pub mod stability;
pub mod stress;
