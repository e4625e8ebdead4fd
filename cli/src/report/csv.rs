//! Trajectory CSV and the number format of every output.

use std::fmt;

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
