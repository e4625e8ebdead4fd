//! Trajectory CSV and the number format of every output.
//!
//! A trajectory file has a header line and one row per point, every number printed by
//! [`Float`] (it reads back exactly). The columns depend on the space: [`csv_header`] on ℝᴺ,
//! [`RIGID_CSV_HEADER`] on SO(3).

use std::fmt;
use std::io::Write;
use std::path::Path;

use crate::report::output::{OutputError, OutputFile};

/// The CSV header line (with its newline) for the given coordinate names.
pub fn csv_header(names: &[String]) -> String {
    let mut header = String::from("t");
    for prefix in ["q", "v", "p"] {
        for name in names {
            header.push_str(&format!(",{prefix}_{name}"));
        }
    }
    header.push_str(",energy\n");
    header
}

/// The CSV header of a rigid-body trajectory (with its newline): time, attitude as a
/// quaternion and as a matrix (row by row), Ω, Π, energy and ‖RᵀR − I‖_F.
pub const RIGID_CSV_HEADER: &str = "t,qw,qx,qy,qz,r11,r12,r13,r21,r22,r23,r31,r32,r33,\
omega_1,omega_2,omega_3,pi_1,pi_2,pi_3,energy,orthogonality\n";

/// A CSV trajectory written row by row as a run computes it: to an [`OutputFile`] created
/// (and its header written) before the first step, so an unwritable path is reported before
/// any work, and renamed into place by [`CsvStream::finish`], so a killed run leaves no torn
/// row; or kept in memory ([`CsvStream::in_memory`], for the Python package).
#[derive(Debug)]
pub struct CsvStream {
    sink: Sink,
    values: Vec<f64>,
    rows: usize,
    last_time: Option<f64>,
}

/// Where a [`CsvStream`]'s rows go.
#[derive(Debug)]
enum Sink {
    File(OutputFile),
    Memory(Recorded),
}

/// A trajectory kept in memory: its column names and its numbers, row by row in one buffer
/// (the Python package hands them to NumPy as they are).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Recorded {
    /// The column names.
    pub columns: Vec<String>,
    /// The numbers, row after row, one per column.
    pub values: Vec<f64>,
}

impl Recorded {
    /// The rows, each with one number per column.
    pub fn rows(&self) -> std::slice::ChunksExact<'_, f64> {
        self.values.chunks_exact(self.columns.len().max(1))
    }
}

impl CsvStream {
    /// Create the output `path` of `option` (a temporary until [`CsvStream::finish`]) and
    /// write `header` (with its newline).
    pub fn create(option: &'static str, path: &Path, header: &str) -> Result<Self, OutputError> {
        let mut out = OutputFile::create(option, path)?;
        out.write_all(header.as_bytes())
            .map_err(|source| OutputError::Write {
                path: path.into(),
                source,
            })?;
        Ok(CsvStream::new(Sink::File(out)))
    }

    /// A stream that keeps its rows in memory, with the columns of `header`.
    pub fn in_memory(header: &str) -> Self {
        let columns = header.trim_end().split(',').map(String::from).collect();
        CsvStream::new(Sink::Memory(Recorded {
            columns,
            values: Vec::new(),
        }))
    }

    fn new(sink: Sink) -> Self {
        CsvStream {
            sink,
            values: Vec::new(),
            rows: 0,
            last_time: None,
        }
    }

    /// Append the row of the point at `time`, whose numbers `fill` puts into its buffer.
    pub fn write_row(
        &mut self,
        time: f64,
        fill: impl FnOnce(&mut Vec<f64>),
    ) -> std::io::Result<()> {
        self.values.clear();
        fill(&mut self.values);
        match &mut self.sink {
            Sink::File(out) => {
                for (i, x) in self.values.iter().enumerate() {
                    let separator = if i == 0 { "" } else { "," };
                    write!(out, "{separator}{}", Float(*x))?;
                }
                writeln!(out)?;
            }
            Sink::Memory(recorded) => recorded.values.extend_from_slice(&self.values),
        }
        self.rows += 1;
        self.last_time = Some(time);
        Ok(())
    }

    /// The rows written so far.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// The time of the last row written.
    pub fn last_time(&self) -> Option<f64> {
        self.last_time
    }

    /// Put the file in place (or hand over the rows kept in memory); the number of rows.
    pub fn finish(self) -> Result<(usize, Option<Recorded>), OutputError> {
        match self.sink {
            Sink::File(out) => {
                out.commit()?;
                Ok((self.rows, None))
            }
            Sink::Memory(recorded) => Ok((self.rows, Some(recorded))),
        }
    }
}

/// An `f64` printed so that it reads back exactly: shortest decimal, in exponent form when
/// very large or small.
#[derive(Debug, Clone, Copy)]
pub struct Float(pub f64);

impl fmt::Display for Float {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x == 0.0 || !x.is_finite() || (1e-5..1e16).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// Comma-separated shortest round-trip values in brackets: `[1, 0.5]`.
pub fn vector(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|x| Float(*x).to_string()).collect();
    format!("[{}]", items.join(", "))
}

/// [`vector`] for messages and the text summary: a vector of more than
/// [`BRIEF_COMPONENTS`] numbers (a chain of 10⁵ particles) shows its first and last few and
/// its length, `[1, 2, 3, 4, …, 97, 98, 99, 100] (100 components)`.
pub fn brief_vector(values: &[f64]) -> String {
    let n = values.len();
    if n <= BRIEF_COMPONENTS {
        return vector(values);
    }
    let shown = BRIEF_COMPONENTS / 2;
    let first = vector(&values[..shown]);
    let last = vector(&values[n - shown..]);
    format!(
        "{}, …, {} ({n} components)",
        &first[..first.len() - 1],
        &last[1..]
    )
}

/// The most components [`brief_vector`] prints in full.
pub const BRIEF_COMPONENTS: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brief_vectors_show_both_ends_of_long_vectors() {
        assert_eq!(brief_vector(&[1.0, 0.5]), "[1, 0.5]");
        let long: Vec<f64> = (1..=100).map(f64::from).collect();
        assert_eq!(
            brief_vector(&long),
            "[1, 2, 3, 4, …, 97, 98, 99, 100] (100 components)"
        );
        assert_eq!(brief_vector(&long[..8]), vector(&long[..8]));
    }

    #[test]
    fn csv_header_prefixes_the_coordinate_names() {
        assert_eq!(
            csv_header(&["q1".into(), "q2".into()]),
            "t,q_q1,q_q2,v_q1,v_q2,p_q1,p_q2,energy\n"
        );
        assert_eq!(csv_header(&["q".into()]), "t,q_q,v_q,p_q,energy\n");
    }

    #[test]
    fn floats_print_to_round_trip() {
        for x in [
            0.0,
            1.0,
            -0.5,
            0.1,
            1.0 / 3.0,
            2000.0,
            1e-300,
            -2.5e-17,
            1e20,
            123456.789,
        ] {
            let text = Float(x).to_string();
            assert_eq!(text.parse::<f64>().unwrap(), x, "{text}");
            assert!(text.len() < 26, "{text}");
        }
        assert_eq!(Float(0.2).to_string(), "0.2");
        assert_eq!(Float(1e-300).to_string(), "1e-300");
    }
}
