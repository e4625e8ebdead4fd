//! The member table of an ensemble (`svi ensemble --out FILE.csv`, `svi.ensemble` in Python):
//! one row per member, in member order.
//!
//! Columns, left to right:
//!
//! - `member`: the member's index (from 0);
//! - one column per varied scene field (the parameter's name, or `q.alpha1` for an initial
//!   component), the member's value;
//! - `status`: `ok`, or the kind of the member's error: the `kind` of `svi run --json`'s
//!   `error` object (`invalid_parameter`, `non_convergence`, `diverged`, ...; `panic` for a
//!   member whose run panicked, which is a bug);
//! - the fields of the member's summary, as `svi run --json` prints them: `t_end`, `steps`,
//!   the final state (`q_NAME`, `v_NAME`, `p_NAME` per coordinate on ℝᴺ; `quaternion_1..4`,
//!   `omega_1..3`, `momentum_1..3` on SO(3)), the energies, the conservation diagnostics,
//!   `iterations`, `evaluations`, `retries` (empty where the summary has no value). A member that
//!   failed after it started has those of its last good state; a member rejected before it
//!   ran has them empty;
//! - `warnings`: the kinds of the failed health checks, `;`-separated;
//! - `error_step`, `error_t`, `error`: where the member failed and the error message.
//!
//! Numbers are printed as [`Float`] prints them (they read back exactly); an absent value is
//! an empty cell. Nothing in the table depends on timing or on the thread count (the run's
//! wall time is in the ensemble's summary, not in a row).

use std::io::Write;

use serde_json::Value;

use crate::report::csv::Float;
use crate::report::summary::{ErrorReport, Summary};

/// What a member's run gave: its summary (complete, or up to its last good state) and its
/// error, if it failed.
#[derive(Debug, Clone, PartialEq)]
pub struct MemberOutcome {
    /// The summary of the run (`None` if the member was rejected before it ran).
    pub summary: Option<Summary>,
    /// Why the member failed.
    pub error: Option<ErrorReport>,
}

impl MemberOutcome {
    /// `ok` or the error's kind.
    pub fn status(&self) -> &'static str {
        self.error.as_ref().map_or("ok", |error| error.kind)
    }
}

/// A cell of the table.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// A number.
    Number(f64),
    /// A count.
    Integer(u64),
    /// Text.
    Text(String),
    /// No value.
    Empty,
}

impl Cell {
    /// The cell as one CSV field (text quoted when it needs to be).
    fn csv(&self) -> String {
        match self {
            Cell::Number(x) => Float(*x).to_string(),
            Cell::Integer(n) => n.to_string(),
            Cell::Text(text) if text.contains([',', '"', '\n', '\r']) => {
                format!("\"{}\"", text.replace('"', "\"\""))
            }
            Cell::Text(text) => text.clone(),
            Cell::Empty => String::new(),
        }
    }

    /// A JSON value: a number, a string or `null`.
    fn from_json(value: &Value) -> Cell {
        match value {
            Value::Number(number) => number
                .as_u64()
                .filter(|_| number.is_u64())
                .map(Cell::Integer)
                .or_else(|| number.as_f64().map(Cell::Number))
                .unwrap_or(Cell::Empty),
            Value::String(text) => Cell::Text(text.clone()),
            _ => Cell::Empty,
        }
    }
}

/// The member table: column names and rows of cells.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Column names.
    pub columns: Vec<String>,
    /// One row per member, one cell per column.
    pub rows: Vec<Vec<Cell>>,
}

/// The scalar fields of a summary that become columns on ℝᴺ, in order.
const VECTOR_SCALARS: [&str; 9] = [
    "energy_initial",
    "energy_final",
    "energy_error_max",
    "energy_scale",
    "momentum_error_max",
    "solution_error_max",
    "iterations",
    "evaluations",
    "retries",
];

/// The scalar fields of a summary that become columns on SO(3), in order.
const RIGID_SCALARS: [&str; 12] = [
    "energy_initial",
    "energy_final",
    "energy_error_max",
    "energy_scale",
    "momentum_error_max",
    "momentum_error_relative",
    "invariant_error_max",
    "orthogonality_error_max",
    "orthogonality_error_final",
    "iterations",
    "evaluations",
    "retries",
];

/// The scalar fields of a summary that become columns on the other Lie groups, in order.
const GROUP_SCALARS: [&str; 12] = [
    "energy_initial",
    "energy_final",
    "energy_error_max",
    "energy_scale",
    "momentum_error_max",
    "momentum_error_relative",
    "solution_error_final",
    "group_defect_max",
    "group_defect_final",
    "iterations",
    "evaluations",
    "retries",
];

/// The columns of a table's summary fields, fixed by the scene's space and model (not by the
/// outcomes: every chunk of an ensemble has the same columns, so chunks run apart — on
/// several machines — concatenate into the table of one run).
#[derive(Debug, Clone, PartialEq)]
pub struct Schema {
    /// (column name, JSON field of the summary, component index of an array field).
    fields: Vec<(String, &'static str, Option<usize>)>,
}

impl Schema {
    /// The columns every table starts with: the run's end and its steps.
    fn leading() -> Vec<(String, &'static str, Option<usize>)> {
        vec![
            ("t_end".into(), "t_end", None),
            ("steps".into(), "steps", None),
        ]
    }

    /// The columns of a model on ℝᴺ with these coordinate names.
    pub fn vector(coordinates: &[String]) -> Schema {
        let mut fields = Schema::leading();
        for field in ["q", "v", "p"] {
            for (i, name) in coordinates.iter().enumerate() {
                fields.push((format!("{field}_{name}"), field, Some(i)));
            }
        }
        fields.extend(VECTOR_SCALARS.map(|field| (field.to_string(), field, None)));
        Schema { fields }
    }

    /// One more column `column`: the summary's JSON field `field` (its component
    /// `component` for an array; `outer.inner` for a field of an object field).
    pub fn add(&mut self, column: String, field: &'static str, component: Option<usize>) {
        self.fields.push((column, field, component));
    }

    /// The columns of a chain of run-time size: its scalars, no column per coordinate (a
    /// chain of 10⁴ sites would have 3·10⁴).
    pub fn chain() -> Schema {
        let mut fields = Schema::leading();
        fields.extend(VECTOR_SCALARS.map(|field| (field.to_string(), field, None)));
        fields.push(("invariant_error_max".into(), "invariant_error_max", None));
        Schema { fields }
    }

    /// The columns of a rigid body on SO(3).
    pub fn rigid() -> Schema {
        let mut fields = Schema::leading();
        for (field, size) in [("quaternion", 4), ("omega", 3), ("momentum", 3)] {
            for i in 0..size {
                fields.push((format!("{field}_{}", i + 1), field, Some(i)));
            }
        }
        fields.extend(RIGID_SCALARS.map(|field| (field.to_string(), field, None)));
        Schema { fields }
    }

    /// The columns of a model on a Lie group of dimension `dimension` whose configuration is
    /// stored as `stored` numbers: g, ξ and μ component by component.
    pub fn group(dimension: usize, stored: usize) -> Schema {
        let mut fields = Schema::leading();
        for (field, size) in [("g", stored), ("xi", dimension), ("momentum", dimension)] {
            for i in 0..size {
                fields.push((format!("{field}_{}", i + 1), field, Some(i)));
            }
        }
        fields.extend(GROUP_SCALARS.map(|field| (field.to_string(), field, None)));
        Schema { fields }
    }
}

impl Table {
    /// The table of `outcomes` of the members numbered from `first`, in order, whose varied
    /// fields are named `axes` and take `values` (one row of values per member), with the
    /// summary columns of `schema`.
    pub fn new(
        schema: &Schema,
        axes: &[String],
        first: usize,
        values: &[Vec<f64>],
        outcomes: &[MemberOutcome],
    ) -> Table {
        let fields = &schema.fields;
        let mut columns: Vec<String> = vec!["member".into()];
        columns.extend(axes.iter().cloned());
        columns.push("status".into());
        columns.extend(fields.iter().map(|(name, _, _)| name.clone()));
        columns.extend(["warnings", "error_step", "error_t", "error"].map(String::from));
        let rows = outcomes
            .iter()
            .zip(values)
            .enumerate()
            .map(|(index, (outcome, values))| {
                let summary =
                    outcome.summary.as_ref().and_then(|summary| {
                        match serde_json::to_value(summary) {
                            Ok(Value::Object(map)) => Some(map),
                            _ => None,
                        }
                    });
                let mut row = vec![Cell::Integer((first + index) as u64)];
                row.extend(values.iter().map(|x| Cell::Number(*x)));
                row.push(Cell::Text(outcome.status().into()));
                for (_, field, component) in fields {
                    // `outer.inner` names a field of an object field.
                    let value = summary
                        .as_ref()
                        .and_then(|map| match field.split_once('.') {
                            Some((outer, inner)) => map.get(outer).and_then(|o| o.get(inner)),
                            None => map.get(*field),
                        });
                    let value = match (value, component) {
                        (Some(Value::Array(items)), Some(i)) => items.get(*i),
                        (value, None) => value,
                        _ => None,
                    };
                    row.push(value.map_or(Cell::Empty, Cell::from_json));
                }
                let warnings = outcome.summary.as_ref().map(|summary| {
                    let kinds: Vec<&str> = summary.warnings.iter().map(|w| w.kind).collect();
                    kinds.join(";")
                });
                row.push(warnings.map_or(Cell::Empty, Cell::Text));
                let error = outcome.error.as_ref();
                row.push(
                    error
                        .and_then(|error| error.step)
                        .map_or(Cell::Empty, |step| Cell::Integer(step as u64)),
                );
                row.push(
                    error
                        .and_then(|error| error.t)
                        .map_or(Cell::Empty, Cell::Number),
                );
                row.push(error.map_or(Cell::Empty, |error| Cell::Text(error.message.clone())));
                row
            })
            .collect();
        Table { columns, rows }
    }

    /// The index of the column `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|column| column == name)
    }

    /// The numbers of column `index` (`None` for a cell without a number).
    pub fn numbers(&self, index: usize) -> Vec<Option<f64>> {
        self.rows
            .iter()
            .map(|row| match row.get(index) {
                Some(Cell::Number(x)) => Some(*x),
                Some(Cell::Integer(n)) => Some(*n as f64),
                _ => None,
            })
            .collect()
    }

    /// Write the table as CSV: a header line, then one line per member.
    pub fn write_csv(&self, out: &mut impl Write) -> std::io::Result<()> {
        writeln!(out, "{}", self.columns.join(","))?;
        for row in &self.rows {
            let fields: Vec<String> = row.iter().map(Cell::csv).collect();
            writeln!(out, "{}", fields.join(","))?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_cells_are_quoted_when_they_must_be() {
        assert_eq!(Cell::Text("a, b".into()).csv(), "\"a, b\"");
        assert_eq!(Cell::Text("say \"x\"".into()).csv(), "\"say \"\"x\"\"\"");
        assert_eq!(Cell::Text("ok".into()).csv(), "ok");
        assert_eq!(Cell::Number(0.1).csv(), "0.1");
        assert_eq!(Cell::Empty.csv(), "");
    }

    #[test]
    fn a_member_rejected_before_it_ran_has_an_empty_state() {
        let rejected = MemberOutcome {
            summary: None,
            error: Some(ErrorReport {
                kind: "invalid_parameter",
                message: "invalid parameter e: 1.2 is outside [0, 1)".into(),
                step: None,
                t: None,
            }),
        };
        let schema = Schema { fields: vec![] };
        let table = Table::new(&schema, &["e".into()], 0, &[vec![1.2]], &[rejected]);
        assert_eq!(
            table.columns,
            [
                "member",
                "e",
                "status",
                "warnings",
                "error_step",
                "error_t",
                "error"
            ]
        );
        let columns = Table::new(&Schema::vector(&["x".to_string()]), &[], 0, &[], &[]).columns;
        assert_eq!(columns[2..7], ["t_end", "steps", "q_x", "v_x", "p_x"]);
        let mut csv = Vec::new();
        table.write_csv(&mut csv).unwrap();
        assert_eq!(
            String::from_utf8(csv).unwrap(),
            "member,e,status,warnings,error_step,error_t,error\n\
             0,1.2,invalid_parameter,,,,\"invalid parameter e: 1.2 is outside [0, 1)\"\n"
        );
    }
}
