//! Trajectory CSV and the number format of every output.
//!
//! A trajectory file has a header line and one row per point, every number printed by
//! [`Float`] (it reads back exactly). The columns depend on the space: [`csv_header`] on ℝᴺ,
//! [`RIGID_CSV_HEADER`] on SO(3).

use std::fmt;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

/// The CSV header line (with its newline) for the given coordinate names.
pub fn csv_header(names: &[&str]) -> String {
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

/// Write `points` as CSV to `path`: `header` (with its newline), then one line per point of
/// the numbers `row` puts into its buffer.
pub fn write_csv<P>(
    path: &Path,
    header: &str,
    points: &[P],
    mut row: impl FnMut(&P, &mut Vec<f64>),
) -> std::io::Result<()> {
    let mut out = BufWriter::new(File::create(path)?);
    out.write_all(header.as_bytes())?;
    let mut values = Vec::new();
    for point in points {
        values.clear();
        row(point, &mut values);
        for (i, x) in values.iter().enumerate() {
            let separator = if i == 0 { "" } else { "," };
            write!(out, "{separator}{}", Float(*x))?;
        }
        writeln!(out)?;
    }
    out.flush()
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_header_prefixes_the_coordinate_names() {
        assert_eq!(
            csv_header(&["q1", "q2"]),
            "t,q_q1,q_q2,v_q1,v_q2,p_q1,p_q2,energy\n"
        );
        assert_eq!(csv_header(&["q"]), "t,q_q,v_q,p_q,energy\n");
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
