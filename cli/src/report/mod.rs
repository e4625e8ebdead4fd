//! What the commands write: the run summary, trajectory CSV and the number format, SVG plots,
//! the progress bar.

pub mod csv;
pub mod plot;
pub mod progress;
pub mod summary;
