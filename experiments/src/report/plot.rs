//! Plots a person can open: SVG line charts, drawn with plotters' SVG backend (no font or
//! system library needed; text is left to the viewer).

use plotters::prelude::*;
use std::path::Path;

use crate::report::output;

/// One curve: a label and its (x, y) points.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Points in drawing order.
    pub points: Vec<(f64, f64)>,
}

/// One chart of a figure.
#[derive(Debug, Clone, PartialEq)]
pub struct Panel {
    /// Title above the chart.
    pub title: String,
    /// Horizontal axis label.
    pub x_label: String,
    /// Vertical axis label.
    pub y_label: String,
    /// Logarithmic horizontal axis.
    pub x_log: bool,
    /// Logarithmic vertical axis.
    pub y_log: bool,
    /// One unit is as long on both axes (orbits in a plane keep their shape); linear axes
    /// only.
    pub equal_scale: bool,
    /// Points only, no lines joining them (a surface of section).
    pub scatter: bool,
    /// The curves.
    pub series: Vec<Series>,
}

/// A plotting failure (file or drawing error), as text.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("cannot draw {path}: {reason}")]
pub struct PlotError {
    /// The file being written.
    pub path: String,
    /// What went wrong.
    pub reason: String,
}

/// Scatter pictures of at most this many series get a legend.
const SCATTER_LEGEND: usize = 8;

/// Series with at most this many points get a marker at each point.
const MARKED_POINTS: usize = 60;

/// Tick label: powers of ten on a log axis, short decimals otherwise (in scientific
/// notation beyond 10⁷ or below 10⁻⁴).
fn tick(value: f64, log: bool) -> String {
    if log || (value != 0.0 && !(1e-4..1e7).contains(&value.abs())) {
        format!("{value:.0e}")
    } else {
        format!("{}", (value * 1e6).round() / 1e6)
    }
}

/// Smallest width of an axis relative to its largest coordinate: plotters' tick search does
/// not end on an axis whose ends agree to round-off (a constant series of 10³⁰⁰, say).
const RELATIVE_WIDTH: f64 = 1e-9;

/// Range of the finite (and, on a log axis, positive) coordinates, padded a little: finite
/// ends, a width at least [`RELATIVE_WIDTH`] of the largest coordinate, and no overflow (a
/// linear axis up to 1.8·10³⁰⁸ is drawn to `f64::MAX / 2`, a log axis within 10^±150).
fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        low = low.min(v);
        high = high.max(v);
    }
    if !low.is_finite() {
        return if log { (1e-16, 1.0) } else { (0.0, 1.0) };
    }
    if log {
        // At least a factor 4, within 10^±150 (a subnormal halved is zero, log 0 = −∞;
        // plotters' ticks do not end on an axis whose ends' ratio overflows).
        let high = (high * 2.0).clamp(1e-146, 1e150);
        ((low / 2.0).clamp(1e-150, high / 4.0), high)
    } else {
        // Midpoint and half-width in halves: neither overflows.
        let (mid, half) = (low / 2.0 + high / 2.0, high / 2.0 - low / 2.0);
        let largest = low.abs().max(high.abs());
        // A twentieth of the width on each side.
        let half = (1.1 * half).max(RELATIVE_WIDTH * largest).max(1e-12);
        let limit = f64::MAX / 2.0;
        ((mid - half).max(-limit), (mid + half).min(limit))
    }
}

/// Draw `panels` side by side into an SVG file of `width` × `height` pixels per panel.
pub fn write_svg(path: &Path, panels: &[Panel], width: u32, height: u32) -> Result<(), PlotError> {
    let svg = render_svg(panels, width, height).map_err(|error| PlotError {
        path: path.display().to_string(),
        reason: error.reason,
    })?;
    write_picture(path, &svg)
}

/// Draw `panels` side by side as the text of an SVG picture of `width` × `height` pixels per
/// panel.
pub fn render_svg(panels: &[Panel], width: u32, height: u32) -> Result<String, PlotError> {
    render_svg_grid(panels, panels.len(), width, height)
}

/// Draw `panels` as the text of an SVG picture of `width` × `height` pixels per panel, in
/// rows of `columns` panels (the last row filled from the left).
pub fn render_svg_grid(
    panels: &[Panel],
    columns: usize,
    width: u32,
    height: u32,
) -> Result<String, PlotError> {
    let error = |reason: String| PlotError {
        path: "the picture".into(),
        reason,
    };
    let columns = columns.clamp(1, panels.len().max(1));
    let rows = panels.len().div_ceil(columns).max(1);
    let mut svg = String::new();
    {
        let size = (width * columns as u32, height * rows as u32);
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| error(e.to_string()))?;
        let areas = root.split_evenly((rows, columns));
        for (panel, area) in panels.iter().zip(areas.iter()) {
            draw_panel(panel, area).map_err(error)?;
        }
        root.present().map_err(|e| error(e.to_string()))?;
    }
    Ok(svg)
}

/// Write the drawn picture `svg` to `path`, atomically ([`output::write_file`]).
fn write_picture(path: &Path, svg: &str) -> Result<(), PlotError> {
    output::write_file("--plot", path, svg.as_bytes()).map_err(|error| PlotError {
        path: path.display().to_string(),
        reason: match &error {
            output::OutputError::Write { source, .. } | output::OutputError::Stdout(source) => {
                source.to_string()
            }
            output::OutputError::Unusable { reason, .. } => reason.clone(),
        },
    })
}

/// A numeric CSV file as written by `svi run --out`: its column names and rows.
fn read_csv(
    csv: &Path,
    error: impl Fn(String) -> PlotError,
) -> Result<(Vec<String>, Vec<Vec<f64>>), PlotError> {
    let text = std::fs::read_to_string(csv)
        .map_err(|e| error(format!("cannot read '{}': {e}", csv.display())))?;
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .enumerate()
        .map(|(row, line)| {
            line.split(',')
                .map(str::parse::<f64>)
                .collect::<Result<Vec<f64>, _>>()
                .map_err(|e| error(format!("row {} of '{}': {e}", row + 1, csv.display())))
        })
        .collect::<Result<_, _>>()?;
    Ok((header, rows))
}

/// Draw the CSV file `csv` (a header of column names, then numeric rows whose first column
/// is t, as `svi run --out` writes them) as one SVG line chart at `svg`: every other column
/// against t, titled `title`.
pub fn plot_csv(csv: &Path, svg: &Path, title: &str) -> Result<(), PlotError> {
    let error = |reason: String| PlotError {
        path: svg.display().to_string(),
        reason,
    };
    let (header, rows) = read_csv(csv, error)?;
    let series = header
        .iter()
        .enumerate()
        .skip(1)
        .map(|(column, name)| Series {
            label: name.clone(),
            points: rows
                .iter()
                .filter_map(|row| Some((row[0], *row.get(column)?)))
                .collect(),
        })
        .collect();
    let panel = Panel {
        title: title.to_string(),
        x_label: "t".into(),
        y_label: header
            .get(1..)
            .map_or(String::new(), |names| names.join(", ")),
        x_log: false,
        y_log: false,
        equal_scale: false,
        scatter: false,
        series,
    };
    write_svg(svg, &[panel], 900, 560)
}

/// Largest number of cells of a space-time picture along x and along t (the field is
/// sampled down to them, so the SVG stays small).
const SPACE_TIME_CELLS: (usize, usize) = (160, 120);

/// A moving mesh of at most this many nodes has every node's path drawn; a finer one every
/// k-th node's, about [`NODE_PATHS`] of them.
const ALL_NODE_PATHS: usize = 101;
/// About how many node paths a space-time picture of a fine moving mesh draws.
const NODE_PATHS: usize = 50;
/// Largest number of points of one drawn node path (its levels are sampled down to them).
const NODE_PATH_POINTS: usize = 400;

/// The nodes whose paths a space-time picture of a moving mesh of `nodes` nodes draws: all
/// of them up to [`ALL_NODE_PATHS`], else every k-th (about [`NODE_PATHS`]) and the last.
fn drawn_node_paths(nodes: usize) -> Vec<usize> {
    if nodes <= ALL_NODE_PATHS {
        return (0..nodes).collect();
    }
    let k = ((nodes - 1) / NODE_PATHS).max(1);
    let mut drawn: Vec<usize> = (0..nodes).step_by(k).collect();
    if drawn.last() != Some(&(nodes - 1)) {
        drawn.push(nodes - 1);
    }
    drawn
}

/// Draw the Poincaré section points of the trajectory files `csvs` (one series per file: an
/// orbit each) as a scatter of their two columns `axes` to `svg`.
///
/// # Errors
/// [`PlotError`] if a file cannot be read or lacks a column, or the picture cannot be written.
pub fn plot_section(
    csvs: &[&Path],
    svg: &Path,
    title: &str,
    axes: &[String; 2],
) -> Result<(), PlotError> {
    let error = |reason: String| PlotError {
        path: svg.display().to_string(),
        reason,
    };
    let mut series = Vec::with_capacity(csvs.len());
    for csv in csvs {
        let (header, rows) = read_csv(csv, error)?;
        let column = |name: &String| {
            header
                .iter()
                .position(|h| h == name)
                .ok_or_else(|| error(format!("{} has no column {name}", csv.display())))
        };
        let (x, y) = (column(&axes[0])?, column(&axes[1])?);
        series.push(Series {
            label: csv
                .file_stem()
                .map_or(String::new(), |stem| stem.to_string_lossy().into_owned()),
            points: rows.iter().map(|row| (row[x], row[y])).collect(),
        });
    }
    let panel = Panel {
        title: title.to_string(),
        x_label: axes[0].clone(),
        y_label: axes[1].clone(),
        x_log: false,
        y_log: false,
        equal_scale: false,
        scatter: true,
        series,
    };
    write_svg(svg, &[panel], 800, 800)
}

/// Draw a field's space-time CSV `csv` (rows `t,x,u` or `t,x,u,…`, the nodes of one time level
/// after another, as `svi run --out` writes a field scene; further columns are ignored, e.g.
/// the real and imaginary parts after |ψ|) as an SVG picture at `svg`: u coloured
/// over the (x, t) plane (blue lowest, white middle, red highest), titled `title` and named
/// by its column (`abs` is drawn as |ψ|). A moving mesh (rows `t,x,u,node`, the node's
/// positions changing from level to level) is coloured cell by cell of the mesh, and the
/// paths x_i(t) of its nodes are drawn over it as thin lines (every node's up to 101 nodes,
/// else about 50 evenly spaced in the node index).
pub fn plot_space_time(csv: &Path, svg: &Path, title: &str) -> Result<(), PlotError> {
    let error = |reason: String| PlotError {
        path: svg.display().to_string(),
        reason,
    };
    let (header, rows) = read_csv(csv, error)?;
    if header.len() < 3 || rows.iter().any(|row| row.len() < 3) {
        return Err(error(format!("'{}' is not a t,x,u table", csv.display())));
    }
    // The nodes of a level share its t: the level's width is the run of equal t's.
    let width = rows.iter().take_while(|row| row[0] == rows[0][0]).count();
    if width < 2 || rows.len() % width != 0 {
        return Err(error(format!(
            "'{}' holds no whole time levels",
            csv.display()
        )));
    }
    let levels = rows.len() / width;
    let moving = header.get(3).is_some_and(|name| name == "node");
    let stride = |count: usize, cells: usize| count.div_ceil(cells).max(1);
    let (x_stride, t_stride) = (
        stride(width, SPACE_TIME_CELLS.0),
        stride(levels, SPACE_TIME_CELLS.1),
    );
    let value = |level: usize, node: usize| rows[level * width + node][2];
    let (low, high) = rows
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), row| {
            (l.min(row[2]), h.max(row[2]))
        });
    let (x0, x1) = (rows[0][1], rows[width - 1][1]);
    let (t0, t1) = (rows[0][0], rows[rows.len() - 1][0]);
    if !(low.is_finite() && high.is_finite() && x1 > x0 && t1 > t0) {
        return Err(error(format!(
            "'{}' has no finite field to draw",
            csv.display()
        )));
    }
    let colour = |u: f64| {
        let s = if high > low {
            (u - low) / (high - low)
        } else {
            0.5
        };
        let mix = |a: f64, b: f64, w: f64| (a + (b - a) * w).round() as u8;
        let (from, to, w) = if s < 0.5 {
            ((59.0, 76.0, 192.0), (247.0, 247.0, 247.0), 2.0 * s)
        } else {
            ((247.0, 247.0, 247.0), (180.0, 4.0, 38.0), 2.0 * s - 1.0)
        };
        RGBColor(
            mix(from.0, to.0, w),
            mix(from.1, to.1, w),
            mix(from.2, to.2, w),
        )
    };
    let mut picture = String::new();
    let draw = |picture: &mut String| -> Result<(), String> {
        let root = SVGBackend::with_string(picture, (900, 640)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        // The drawn column by its name: u for a real field, |ψ| for a complex one.
        let name = match header[2].as_str() {
            "abs" => "|ψ|",
            other => other,
        };
        let paths = if moving { "; lines: node paths" } else { "" };
        let caption = format!("{title}: {name} from {low:.3} (blue) to {high:.3} (red){paths}");
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(x0..x1, t0..t1)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("x")
            .y_desc("t")
            .disable_mesh()
            .draw()
            .map_err(|e| e.to_string())?;
        let cells = (0..levels)
            .step_by(t_stride)
            .flat_map(|level| (0..width).step_by(x_stride).map(move |node| (level, node)));
        let corner = |l: usize, n: usize| (rows[n + l * width][1], rows[l * width][0]);
        if moving {
            // The cells of the moving mesh: quadrilaterals between the nodes' positions at
            // the two levels (they tile the plane, the nodes being ordered at every level).
            chart
                .draw_series(cells.map(|(level, node)| {
                    let (right, top) = (
                        (node + x_stride).min(width - 1),
                        (level + t_stride).min(levels - 1),
                    );
                    Polygon::new(
                        vec![
                            corner(level, node),
                            corner(level, right),
                            corner(top, right),
                            corner(top, node),
                        ],
                        colour(value(level, node)).filled(),
                    )
                }))
                .map_err(|e| e.to_string())?;
            let path_stride = stride(levels, NODE_PATH_POINTS);
            let mut path_levels: Vec<usize> = (0..levels).step_by(path_stride).collect();
            if path_levels.last() != Some(&(levels - 1)) {
                path_levels.push(levels - 1);
            }
            for node in drawn_node_paths(width) {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        path_levels
                            .iter()
                            .map(|&level| corner(level, node))
                            .collect::<Vec<_>>(),
                        BLACK.mix(0.45).stroke_width(1),
                    )))
                    .map_err(|e| e.to_string())?;
            }
        } else {
            chart
                .draw_series(cells.map(|(level, node)| {
                    let (right, top) = (
                        (node + x_stride).min(width - 1),
                        (level + t_stride).min(levels - 1),
                    );
                    Rectangle::new(
                        [corner(level, node), corner(top, right)],
                        colour(value(level, node)).filled(),
                    )
                }))
                .map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())
    };
    draw(&mut picture).map_err(error)?;
    write_picture(svg, &picture)
}

/// A panel's margin, in pixels.
const MARGIN: u32 = 12;
/// The height of the horizontal axis' labels, in pixels.
const X_LABELS: u32 = 45;
/// The width of the vertical axis' labels, in pixels.
const Y_LABELS: u32 = 70;
/// About the height of a panel's caption (18-pixel text), in pixels.
const CAPTION: u32 = 28;

/// The ranges `x` and `y` widened about their midpoints so that one unit takes as many of
/// the `pixels` (width, height) of the plotting area on both axes (within ±`f64::MAX / 2`,
/// as [`range`]).
fn equal_scale(x: (f64, f64), y: (f64, f64), pixels: (f64, f64)) -> ((f64, f64), (f64, f64)) {
    let per_pixel = ((x.1 - x.0) / pixels.0).max((y.1 - y.0) / pixels.1);
    let widen = |(low, high): (f64, f64), pixels: f64| {
        let (mid, half) = (low / 2.0 + high / 2.0, per_pixel * pixels / 2.0);
        let limit = f64::MAX / 2.0;
        ((mid - half).max(-limit), (mid + half).min(limit))
    };
    (widen(x, pixels.0), widen(y, pixels.1))
}

fn draw_panel(
    panel: &Panel,
    area: &DrawingArea<SVGBackend, plotters::coord::Shift>,
) -> Result<(), String> {
    let points = || panel.series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1) = range(points().map(|p| p.0), panel.x_log);
    let (mut y0, mut y1) = range(points().map(|p| p.1), panel.y_log);
    if panel.equal_scale && !panel.x_log && !panel.y_log {
        let (width, height) = area.dim_in_pixel();
        let pixels = (
            f64::from(width.saturating_sub(MARGIN * 2 + Y_LABELS)).max(1.0),
            f64::from(height.saturating_sub(MARGIN * 2 + X_LABELS + CAPTION)).max(1.0),
        );
        ((x0, x1), (y0, y1)) = equal_scale((x0, x1), (y0, y1), pixels);
    }
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(&panel.title, ("sans-serif", 18))
        .margin(MARGIN)
        .x_label_area_size(X_LABELS)
        .y_label_area_size(Y_LABELS);
    macro_rules! draw {
        ($x:expr, $y:expr) => {{
            let mut chart = builder
                .build_cartesian_2d($x, $y)
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(panel.x_label.as_str())
                .y_desc(panel.y_label.as_str())
                .x_label_formatter(&|v| tick(*v, panel.x_log))
                .y_label_formatter(&|v| tick(*v, panel.y_log))
                .draw()
                .map_err(|e| e.to_string())?;
            for (index, series) in panel.series.iter().enumerate() {
                let color = Palette99::pick(index).to_rgba();
                let data: Vec<(f64, f64)> = series
                    .points
                    .iter()
                    .copied()
                    .filter(|(x, y)| {
                        x.is_finite()
                            && y.is_finite()
                            && (!panel.x_log || *x > 0.0)
                            && (!panel.y_log || *y > 0.0)
                    })
                    .collect();
                if panel.scatter {
                    let drawn = chart
                        .draw_series(data.into_iter().map(|p| Circle::new(p, 1, color.filled())))
                        .map_err(|e| e.to_string())?;
                    // A legend of many orbits would cover the picture: colours tell them apart.
                    if panel.series.len() <= SCATTER_LEGEND {
                        drawn
                            .label(series.label.as_str())
                            .legend(move |(x, y)| Circle::new((x + 10, y), 3, color.filled()));
                    }
                    continue;
                }
                chart
                    .draw_series(LineSeries::new(data.clone(), color.stroke_width(2)))
                    .map_err(|e| e.to_string())?
                    .label(series.label.as_str())
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                    });
                if data.len() <= MARKED_POINTS {
                    chart
                        .draw_series(data.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                        .map_err(|e| e.to_string())?;
                }
            }
            if !(panel.scatter && panel.series.len() > SCATTER_LEGEND) {
                chart
                    .configure_series_labels()
                    .background_style(WHITE.mix(0.8))
                    .border_style(BLACK)
                    .draw()
                    .map_err(|e| e.to_string())?;
            }
        }};
    }
    match (panel.x_log, panel.y_log) {
        (true, true) => draw!((x0..x1).log_scale(), (y0..y1).log_scale()),
        (true, false) => draw!((x0..x1).log_scale(), y0..y1),
        (false, true) => draw!(x0..x1, (y0..y1).log_scale()),
        (false, false) => draw!(x0..x1, y0..y1),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Axes that plotters' tick search never finished on (a stability plot up to z =
    /// 1.8·10³⁰⁸ ran forever), or that overflow: drawn, with finite ranges of a width it
    /// resolves.
    #[test]
    fn extreme_and_constant_coordinates_are_drawn() {
        let extremes: [&[f64]; 6] = [
            &[1e300, 1e300],
            &[3.4e18, f64::MAX],
            &[-f64::MAX, f64::MAX],
            &[5e-324, f64::MAX],
            &[1.0, 1.0 + 1e-15],
            &[-0.0, 0.0],
        ];
        for values in extremes {
            for log in [false, true] {
                let (low, high) = range(values.iter().copied(), log);
                assert!(
                    low.is_finite() && high.is_finite() && low < high,
                    "{values:?}"
                );
                assert!(
                    high - low >= RELATIVE_WIDTH * low.abs().max(high.abs()),
                    "{values:?}"
                );
            }
            let points: Vec<(f64, f64)> = values.iter().map(|&v| (v, v)).collect();
            for (x_log, y_log) in [(false, false), (true, true)] {
                let panel = Panel {
                    title: "extreme".into(),
                    x_label: "x".into(),
                    y_label: "y".into(),
                    x_log,
                    y_log,
                    equal_scale: false,
                    scatter: false,
                    series: vec![Series {
                        label: "s".into(),
                        points: points.clone(),
                    }],
                };
                let svg = render_svg(&[panel], 300, 200).unwrap();
                assert!(svg.contains("extreme"));
            }
        }
    }

    #[test]
    fn writes_an_svg_with_every_series_label() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("plot.svg");
        let panel = |log| Panel {
            title: "test".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            x_log: log,
            y_log: log,
            equal_scale: false,
            scatter: false,
            series: vec![
                Series {
                    label: "first".into(),
                    points: vec![(1e-3, 1e-2), (1e-2, 1e-6), (0.0, f64::NAN)],
                },
                Series {
                    label: "second".into(),
                    points: vec![(2e-3, 1e-3), (3e-2, 1e-9)],
                },
            ],
        };
        write_svg(&path, &[panel(true), panel(false)], 400, 300).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("<svg"));
        assert_eq!(text.matches(">\nfirst\n<").count(), 2, "{text}");
        assert_eq!(text.matches(">\nsecond\n<").count(), 2);
    }
}
