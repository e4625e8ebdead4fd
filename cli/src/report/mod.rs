//! What the commands write: SVG plots.

pub mod plot;
