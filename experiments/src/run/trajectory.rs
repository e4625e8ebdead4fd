//! The trajectory of a run, written as the run goes: to its CSV file, or kept in memory.

use std::marker::PhantomData;
use std::ops::ControlFlow;
use std::path::Path;

use svi::method::space::Space;
use svi::observer::Observer;

use crate::report::csv::{CsvStream, Recorded};
use crate::report::summary::TrajectoryOutput;
use crate::run::space::RunSpace;
use crate::scene::SceneError;

/// The trajectory of a run on the space `S`, written as the run goes (to its file, or kept in
/// memory): an observer of the thinned step points (a write error stops the run and is
/// reported after it).
pub(super) struct TrajectoryStream<S> {
    path: std::path::PathBuf,
    stream: CsvStream,
    error: Option<std::io::Error>,
    space: PhantomData<S>,
}

impl<S: Space> TrajectoryStream<S> {
    /// Create the file at `path` with the header of the space (or, with `path` empty, keep
    /// the rows in memory).
    pub(super) fn create<L>(model: &L, path: &Path, record: bool) -> Result<Self, SceneError>
    where
        S: RunSpace<L>,
    {
        let header = S::csv_header(model);
        let stream = if record {
            CsvStream::in_memory(&header)
        } else {
            CsvStream::create("--out (output.trajectory)", path, &header)?
        };
        Ok(TrajectoryStream {
            path: path.into(),
            stream,
            error: None,
            space: PhantomData,
        })
    }

    /// Append the row of `point`.
    pub(super) fn write<L>(&mut self, model: &L, point: &S::Point) -> Result<(), SceneError>
    where
        S: RunSpace<L>,
    {
        let result = self
            .stream
            .write_row(S::time(point), |row| S::csv_row(model, point, row));
        result.map_err(|source| self.failed(source))
    }

    /// The time of the last row written.
    pub(super) fn last_time(&self) -> Option<f64> {
        self.stream.last_time()
    }

    /// Put the file in place (or report the write error that stopped the run); the rows kept
    /// in memory.
    pub(super) fn finish(
        self,
        every: usize,
    ) -> Result<(TrajectoryOutput, Option<Recorded>), SceneError> {
        if let Some(source) = self.error {
            return Err(SceneError::Write {
                path: self.path,
                source,
            });
        }
        let (rows, recorded) = self.stream.finish()?;
        let path = self.path.display().to_string();
        Ok((TrajectoryOutput { path, every, rows }, recorded))
    }

    /// The error of a failed write, as a scene error.
    fn failed(&self, source: std::io::Error) -> SceneError {
        SceneError::Write {
            path: self.path.clone(),
            source,
        }
    }
}

impl<L, S: RunSpace<L>> Observer<L, S::Point> for TrajectoryStream<S> {
    fn observe(&mut self, model: &L, _: usize, point: &S::Point) -> ControlFlow<()> {
        let result = self
            .stream
            .write_row(S::time(point), |row| S::csv_row(model, point, row));
        match result {
            Ok(()) => ControlFlow::Continue(()),
            Err(error) => {
                self.error = Some(error);
                ControlFlow::Break(())
            }
        }
    }
}
