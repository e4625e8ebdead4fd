//! Methods on Hamilton's equations (placeholder module file; merged with the segment methods).

pub mod galerkin;
