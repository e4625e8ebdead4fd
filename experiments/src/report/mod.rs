//! What the commands write: the run summary and its health check, trajectory CSV and the
//! number format, SVG plots, the progress bar.

pub mod chaos;
pub mod csv;
pub mod events;
pub mod field;
pub mod health;
pub mod map;
pub mod output;
pub mod plot;
pub mod progress;
pub mod schema;
pub mod sensitivity;
pub mod spectral;
pub mod summary;
pub mod table;
