//! The integration tests of svi-experiments: what runs a scene, through the library's public
//! interface, in one binary.
//!
//! A unit test that runs a scene ([`svi_experiments::Scene::run`] and what calls it) belongs
//! here, not in the crate: it makes the unit-test build compile every model with every method
//! again (the crate's unit tests took 311 s to compile with two such tests, 32 s without;
//! `cargo test --release -p svi-experiments --lib --no-run`), where this binary links the
//! library's.

mod gradient;
