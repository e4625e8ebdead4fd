//! Tests of the `svi` command: the binary run as a user runs it, and the library in process.
//!
//! All integration tests of this crate are modules of this one test binary (`cargo test
//! --release --test integration [FILTER]`): one link, and each generic function the tests
//! share is compiled once instead of once per file.

#[path = "../../tests/common/allocations.rs"]
mod allocations;
mod common;
#[path = "../../tests/common/hostile_cases.rs"]
mod hostile_cases;
#[path = "common/hostile.rs"]
mod hostile_support;

mod cli;
mod compare;
mod constraints;
mod ensemble;
mod events;
mod field;
mod front_doors;
mod groups;
mod help;
mod honesty;
mod hostile;
mod hostile_surfaces;
mod in_process;
mod limits;
mod local;
mod rigid;
mod sensitivity;
mod spectral;
mod stress;
mod text;
