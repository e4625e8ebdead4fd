//! `svi stability`: linear stability of a method on the harmonic oscillator, z = σ²h².
//!
//! Evaluates the stability matrix S(z) of [`svi::stability`] (from the method's tangent map)
//! on a z grid or at listed z values, writes CSV, plots ρ(S), det S, tr(S)² − 4 det S and
//! |tr S| − det S − 1 against z as SVG (Li, Wu, Leok 2018, Figs. 3–6), and prints the
//! stability, periodicity and strong-stability regions of Definition 4.1.

use crate::report::output::{self, OutputDirectory};
use crate::report::plot::{Panel, Series, render_svg};
use crate::scene::SceneError;
use crate::scene::limits::{self, MAX_SAMPLES};
use crate::scene::overrides::method_help;
use nalgebra::U1;
use std::fmt::Write as _;
use std::path::Path;
use svi::method::registry::VectorMethodVisitor;
use svi::stability::{Interval, StabilityPoint, StabilityReport, analyse, stability_matrix};
use svi::{Method, MethodSpec};

/// The configurations of the paper's Figs. 3–6: (label, method).
pub fn figure_configurations() -> Vec<(&'static str, MethodSpec)> {
    [
        ("Cheb 5, Gau 4", "svi:5/4"),
        ("Cheb 5, Gau 10", "svi:5/10"),
        ("Cheb 9, Gau 8", "svi:9/8"),
        ("Cheb 9, Gau 18", "svi:9/18"),
        ("SC, Cheb 5", "sc:5"),
        ("SC, Cheb 9", "sc:9"),
    ]
    .into_iter()
    .filter_map(|(label, spec)| Some((label, spec.parse().ok()?)))
    .collect()
}

/// S(z) diagnostics at each listed z.
pub fn evaluate<M: Method<U1>>(
    method: &M,
    values: &[f64],
) -> Result<Vec<StabilityPoint>, svi::Error> {
    values
        .iter()
        .map(|&z| stability_matrix(method, z).map(|matrix| StabilityPoint::new(z, matrix)))
        .collect()
}

/// CSV with a header row: `z,rho,det,trace,discriminant,strong_margin`.
pub fn to_csv(points: &[StabilityPoint]) -> String {
    let mut text = String::from("z,rho,det,trace,discriminant,strong_margin\n");
    for p in points {
        let _ = writeln!(
            text,
            "{:e},{:e},{:e},{:e},{:e},{:e}",
            p.z, p.rho, p.det, p.trace, p.discriminant, p.strong_margin
        );
    }
    text
}

fn intervals(list: &[Interval]) -> String {
    if list.is_empty() {
        return "none".into();
    }
    list.iter()
        .map(|i| format!("[{}, {}]", fixed(i.lower), fixed(i.upper)))
        .collect::<Vec<_>>()
        .join(" ∪ ")
}

/// `x` with ten decimals, or in exponent form where that would print dozens of digits or
/// none that count (|x| ≥ 10¹⁶ or below 10⁻¹⁰).
fn fixed(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-10..1e16).contains(&x.abs()) {
        format!("{x:.10}")
    } else {
        format!("{x:.10e}")
    }
}

/// `x` as `{}` prints it, or in exponent form where that would print dozens of digits
/// (|x| ≥ 10¹⁶ or below 10⁻⁷).
fn plain(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-7..1e16).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The regions of a report as text.
pub fn describe(label: &str, report: &StabilityReport) -> String {
    format!(
        "{label} on z ∈ [{}, {}]:\n  stable          {}\n  periodic        {}\n  strongly stable {}\n  A-stable: {}, P-stable: {}\n",
        plain(report.range.lower),
        plain(report.range.upper),
        intervals(&report.stable),
        intervals(&report.periodic),
        intervals(&report.strongly_stable),
        if report.a_stable { "yes" } else { "no" },
        if report.p_stable { "yes" } else { "no" },
    )
}

/// The four diagnostics against z, one curve per labelled report, as SVG.
pub fn plot(
    reports: &[(String, StabilityReport)],
) -> Result<String, crate::report::plot::PlotError> {
    type Pick = fn(&StabilityPoint) -> f64;
    let quantities: [(&str, Pick); 4] = [
        ("spectral radius ρ(S)", |p| p.rho),
        ("det S", |p| p.det),
        ("tr(S)² − 4 det S", |p| p.discriminant),
        ("|tr S| − det S − 1", |p| p.strong_margin),
    ];
    let panels: Vec<Panel> = quantities
        .iter()
        .map(|(name, pick)| Panel {
            title: (*name).into(),
            x_label: "z = σ²h²".into(),
            y_label: (*name).into(),
            x_log: false,
            y_log: false,
            equal_scale: false,
            scatter: false,
            series: reports
                .iter()
                .map(|(label, report)| Series {
                    label: label.clone(),
                    points: report.points.iter().map(|p| (p.z, pick(p))).collect(),
                })
                .collect(),
        })
        .collect();
    render_svg(&panels, 520, 420)
}

/// Analyse `method` on [z_min, z_max] with `samples` grid points.
pub fn report<M: Method<U1>>(
    method: &M,
    z_min: f64,
    z_max: f64,
    samples: usize,
) -> Result<StabilityReport, svi::Error> {
    analyse(method, z_min, z_max, samples)
}

/// What to compute for one method (see [`Request::check`] for the limits).
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// Regions and curves on [z_min, z_max] with `samples` grid points.
    Range {
        /// Lower end.
        z_min: f64,
        /// Upper end.
        z_max: f64,
        /// Grid points.
        samples: usize,
    },
    /// Exactly these z values.
    Values(Vec<f64>),
}

/// The longest analysis `svi stability` runs, in seconds ([`estimated_seconds`]): 10 minutes.
pub const MAX_ESTIMATED_SECONDS: f64 = 600.0;

/// The estimated time of analysing `spec` at `samples` values of z, in seconds: per value
/// 2.5·10⁻⁷ s × P² max(P, M) for a method of P CGL points and M Gauss points (the stage
/// system of the oscillator, assembled and factorised), 10⁻⁵ s for the classic methods;
/// measured on a 2-core machine for svi:P/P, P = 16 … 128 (svi:128/128: 0.49 s a value) and
/// sc:64, sc:128 (2026-11-27).
pub fn estimated_seconds(spec: MethodSpec, samples: usize) -> f64 {
    let per_value = match spec.points_in_use() {
        Some(points) => {
            let p = points as f64;
            let m = spec.quadrature_in_use().unwrap_or(points) as f64;
            2.5e-7 * p * p * p.max(m)
        }
        None => 1e-5,
    };
    per_value * samples as f64
}

impl Request {
    /// Check the request's size: at most [`MAX_SAMPLES`] grid points (the z values are the
    /// library's to check), and for `spec` an analysis estimated at most
    /// [`MAX_ESTIMATED_SECONDS`]. An error names `--samples` (or `--z`).
    pub fn check(&self, spec: MethodSpec) -> Result<(), SceneError> {
        let (option, count) = match self {
            Request::Range { samples, .. } => {
                limits::count("--samples", *samples, 2, MAX_SAMPLES, "grid points")?;
                ("--samples", *samples)
            }
            Request::Values(values) => ("--z", values.len()),
        };
        let estimate = estimated_seconds(spec, count);
        if estimate > MAX_ESTIMATED_SECONDS {
            return Err(SceneError::InvalidOption {
                option,
                reason: format!(
                    "{count} values of z with {spec} would take about {:.0} s on a 2-core \
                     machine, more than the {MAX_ESTIMATED_SECONDS} s svi stability runs; \
                     take fewer samples or fewer points",
                    estimate
                ),
            });
        }
        Ok(())
    }
}

/// `svi stability`'s arguments (parsed by the binary, and by tests as the binary does).
#[derive(Debug, Clone, PartialEq, clap::Args)]
pub struct StabilityArgs {
    /// Method: NAME, NAME:P or NAME:P/M, e.g. svi:5/4, sc:9, verlet (see --help).
    #[arg(
        long,
        value_name = "METHOD",
        default_value = "svi:5/4",
        long_help = method_help("Method (for models on ℝᴺ; not with --figures)."),
        conflicts_with = "figures"
    )]
    pub method: String,
    /// Evaluate exactly these z values (comma-separated) and print CSV to stdout (instead of
    /// the range: not with --z-min, --z-max, --samples, --figures, --out-dir).
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        conflicts_with_all = ["z_min", "z_max", "samples", "figures", "out_dir"]
    )]
    pub z: Option<Vec<f64>>,
    /// Lower end of the z range.
    #[arg(long, default_value_t = 1e-6, allow_hyphen_values = true)]
    pub z_min: f64,
    /// Upper end of the z range.
    #[arg(long, default_value_t = 900.0, allow_hyphen_values = true)]
    pub z_max: f64,
    /// Grid points on the z range.
    #[arg(
        long,
        default_value_t = 900,
        allow_hyphen_values = true,
        help = format!(
            "Grid points on the z range, 2 to {MAX_SAMPLES}; an analysis estimated above \
             {MAX_ESTIMATED_SECONDS} s (about 2.5e-7 s × P² max(P, M) per point for P CGL and M \
             Gauss points) is refused with its estimate"
        )
    )]
    pub samples: usize,
    /// The six configurations of the paper's Figs. 3–6 instead of --method (not with
    /// --method or --z).
    #[arg(long)]
    pub figures: bool,
    /// Directory for `stability.csv` (one method) and `stability.svg`.
    #[arg(long, default_value = "stability-out")]
    pub out_dir: std::path::PathBuf,
}

impl StabilityArgs {
    /// The request these arguments make: the listed z values, or the range.
    pub fn request(&self) -> Request {
        match &self.z {
            Some(values) => Request::Values(values.clone()),
            None => Request::Range {
                z_min: self.z_min,
                z_max: self.z_max,
                samples: self.samples,
            },
        }
    }
}

/// The answer to a [`Request`].
#[derive(Debug, Clone, PartialEq)]
pub enum Answer {
    /// A full report.
    Report(StabilityReport),
    /// The listed points.
    Points(Vec<StabilityPoint>),
}

/// Run `request` for the method `spec` (a method for models on ℝᴺ; an error names a
/// rigid-body method) after checking it ([`Request::check`]).
pub fn run(spec: MethodSpec, request: &Request) -> Result<Answer, SceneError> {
    request.check(spec)?;
    /// Answers the request for the visited method.
    struct Answering<'a>(&'a Request);
    impl VectorMethodVisitor<U1> for Answering<'_> {
        type Output = Result<Answer, svi::Error>;
        fn visit<M: Method<U1> + Clone>(self, method: M) -> Self::Output {
            match self.0 {
                Request::Range {
                    z_min,
                    z_max,
                    samples,
                } => report(&method, *z_min, *z_max, *samples).map(Answer::Report),
                Request::Values(values) => evaluate(&method, values).map(Answer::Points),
            }
        }
    }
    Ok(Answering(request).visit(spec.vector_method()?)?)
}

/// `svi stability` with the arguments `args`: [`execute`] on their method, request, figures
/// and output directory.
pub fn execute_args(args: &StabilityArgs) -> anyhow::Result<()> {
    execute(&args.method, args.request(), args.figures, &args.out_dir)
}

/// `svi stability`: for listed z values, print the CSV of `method`; for a range, print the
/// regions of `method` (or of the paper's six configurations with `figures`) and write
/// `stability.csv` (one method) and `stability.svg` into `out_dir`.
pub fn execute(
    method: &str,
    request: Request,
    figures: bool,
    out_dir: &Path,
) -> anyhow::Result<()> {
    if let Request::Values(_) = request {
        let spec: MethodSpec = method.parse()?;
        if let Answer::Points(points) = run(spec, &request)? {
            output::print(to_csv(&points)).map_err(SceneError::from)?;
        }
        return Ok(());
    }
    let configurations: Vec<(String, MethodSpec)> = if figures {
        figure_configurations()
            .into_iter()
            .map(|(label, spec)| (label.to_string(), spec))
            .collect()
    } else {
        vec![(method.to_string(), method.parse()?)]
    };
    let mut names = vec!["stability.svg".to_string()];
    if !figures {
        names.push("stability.csv".into());
    }
    let mut dir =
        OutputDirectory::create("--out-dir", out_dir, &names, &[]).map_err(SceneError::from)?;
    let mut reports = Vec::new();
    for (label, spec) in configurations {
        if let Answer::Report(report) = run(spec, &request)? {
            output::print(describe(&label, &report)).map_err(SceneError::from)?;
            reports.push((label, report));
        }
    }
    if let [(_, report)] = reports.as_slice() {
        dir.write("stability.csv", to_csv(&report.points).as_bytes())
            .map_err(SceneError::from)?;
    }
    dir.write("stability.svg", plot(&reports)?.as_bytes())
        .map_err(SceneError::from)?;
    dir.commit().map_err(SceneError::from)?;
    for name in names.iter().rev() {
        output::warn(format_args!("wrote {}", out_dir.join(name).display()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use svi::Svi;

    #[test]
    fn csv_lists_the_requested_points_and_linear_svi_is_stable_below_twelve() {
        let method = Svi::new(2).with_quadrature(2);
        let points = evaluate(&method, &[0.5, 1.0, 11.0, 13.0]).unwrap();
        let csv = to_csv(&points);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "z,rho,det,trace,discriminant,strong_margin");
        assert_eq!(lines.len(), 5);
        // tr S = 2 − 6z/(6 + z) for degree 1 with two Gauss points; det S = 1.
        for p in &points {
            assert!((p.trace - (2.0 - 6.0 * p.z / (6.0 + p.z))).abs() < 1e-12);
            assert!((p.det - 1.0).abs() < 1e-12);
        }
        assert!((points[2].rho - 1.0).abs() < 1e-12);
        assert!(points[3].rho > 1.0 + 1e-3);
    }

    #[test]
    fn describe_names_the_regions() {
        let report = report(&Svi::new(2).with_quadrature(2), 1e-6, 20.0, 50).unwrap();
        let text = describe("Cheb 2, Gau 2", &report);
        assert!(
            text.contains("stable          [0.0000010000, 12.0000000000]"),
            "{text}"
        );
        assert!(text.contains("A-stable: no"));
    }
}
