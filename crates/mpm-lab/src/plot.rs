//! Minimal SVG line plots for the reports: no dependency, axes with
//! decade or linear ticks (the axes end on labelled ticks), polylines with
//! markers per series, a cross for each failed run, an optional horizontal
//! reference line, a legend.

use std::fmt::Write;

/// One curve: its label, points, colour and whether it is dashed. A point
/// with a NaN value is a failed run: it is marked with a cross on the
/// bottom axis and breaks the line.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    pub colour: &'static str,
    pub dashed: bool,
}

/// A plot's title, axis labels and scales.
pub struct Plot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    /// A horizontal line at a known value (e.g. a finite-element solution),
    /// with its label.
    pub reference: Option<(String, f64)>,
}

const WIDTH: f64 = 720.0;
const HEIGHT: f64 = 460.0;
const LEFT: f64 = 80.0;
const RIGHT: f64 = 220.0;
const TOP: f64 = 40.0;
const BOTTOM: f64 = 60.0;

/// Colours for series, in order.
pub const COLOURS: [&str; 6] = [
    "#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b",
];

impl Plot {
    /// The plot as an SVG document. Points that cannot be drawn (non-finite,
    /// or not positive on a log axis) are left out.
    pub fn svg(&self, series: &[Series]) -> String {
        let tx = |v: f64| if self.log_x { v.log10() } else { v };
        let ty = |v: f64| if self.log_y { v.log10() } else { v };
        let drawable = |&(x, y): &(f64, f64)| {
            x.is_finite() && y.is_finite() && (!self.log_x || x > 0.0) && (!self.log_y || y > 0.0)
        };
        let failed = |&(x, y): &(f64, f64)| y.is_nan() && x.is_finite() && (!self.log_x || x > 0.0);
        let all: Vec<(f64, f64)> = series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| drawable(p)))
            .map(|&(x, y)| (tx(x), ty(y)))
            .collect();
        let failed_x = series
            .iter()
            .flat_map(|s| s.points.iter().filter(|p| failed(p)))
            .map(|&(x, _)| tx(x));
        let reference = self
            .reference
            .as_ref()
            .filter(|(_, y)| y.is_finite() && (!self.log_y || *y > 0.0))
            .map(|(_, y)| ty(*y));
        let (x0, x1) = range(all.iter().map(|p| p.0).chain(failed_x), self.log_x);
        let (y0, y1) = range(all.iter().map(|p| p.1).chain(reference), self.log_y);
        let plot_w = WIDTH - LEFT - RIGHT;
        let plot_h = HEIGHT - TOP - BOTTOM;
        let px = |v: f64| LEFT + (v - x0) / (x1 - x0) * plot_w;
        let py = |v: f64| TOP + (y1 - v) / (y1 - y0) * plot_h;

        let mut s = String::new();
        let _ = writeln!(
            s,
            r#"<svg xmlns="http://www.w3.org/2000/svg" width="{WIDTH}" height="{HEIGHT}" font-family="sans-serif" font-size="12">"#
        );
        let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
        let _ = writeln!(
            s,
            r#"<text x="{}" y="22" text-anchor="middle" font-size="14">{}</text>"#,
            LEFT + plot_w / 2.0,
            escape(&self.title)
        );
        let _ = writeln!(
            s,
            r#"<rect x="{LEFT}" y="{TOP}" width="{plot_w}" height="{plot_h}" fill="none" stroke="black"/>"#
        );
        for (v, label) in ticks(x0, x1, self.log_x) {
            let x = px(v);
            let _ = writeln!(
                s,
                r##"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{label}</text>"##,
                TOP + plot_h,
                TOP + plot_h + 16.0
            );
        }
        for (v, label) in ticks(y0, y1, self.log_y) {
            let y = py(v);
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{:.1}" y="{:.1}" text-anchor="end">{label}</text>"##,
                LEFT + plot_w,
                LEFT - 6.0,
                y + 4.0
            );
        }
        let _ = writeln!(
            s,
            r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
            LEFT + plot_w / 2.0,
            HEIGHT - 18.0,
            escape(&self.x_label)
        );
        let _ = writeln!(
            s,
            r#"<text transform="translate(18 {}) rotate(-90)" text-anchor="middle">{}</text>"#,
            TOP + plot_h / 2.0,
            escape(&self.y_label)
        );
        let mut legend = 0;
        let mut legend_y = || {
            legend += 1;
            TOP + 10.0 + 18.0 * (legend - 1) as f64
        };
        let lx = WIDTH - RIGHT + 12.0;
        if let (Some((label, _)), Some(y)) = (&self.reference, reference) {
            let y = py(y);
            let ly = legend_y();
            let _ = writeln!(
                s,
                r##"<line x1="{LEFT}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#444" stroke-width="1.5" stroke-dasharray="2 3"/>"##,
                LEFT + plot_w
            );
            let _ = writeln!(
                s,
                r##"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="#444" stroke-width="1.5" stroke-dasharray="2 3"/><text x="{}" y="{}">{}</text>"##,
                lx + 24.0,
                lx + 30.0,
                ly + 4.0,
                escape(label)
            );
        }
        let mut any_failed = false;
        for series in series {
            let dash = if series.dashed {
                r#" stroke-dasharray="6 4""#
            } else {
                ""
            };
            // A line through each run of drawable points: a failed run
            // (a NaN value, placed or not) breaks it.
            for run in series.points.split(|p| p.1.is_nan()) {
                let pts: Vec<(f64, f64)> = run
                    .iter()
                    .filter(|p| drawable(p))
                    .map(|&(x, y)| (px(tx(x)), py(ty(y))))
                    .collect();
                let path: Vec<String> = pts.iter().map(|(x, y)| format!("{x:.1},{y:.1}")).collect();
                let _ = writeln!(
                    s,
                    r#"<polyline points="{}" fill="none" stroke="{}" stroke-width="1.5"{dash}/>"#,
                    path.join(" "),
                    series.colour
                );
                for (x, y) in &pts {
                    let _ = writeln!(
                        s,
                        r#"<circle cx="{x:.1}" cy="{y:.1}" r="3" fill="{}"/>"#,
                        series.colour
                    );
                }
            }
            for &(x, _) in series.points.iter().filter(|p| failed(p)) {
                any_failed = true;
                let _ = writeln!(s, "{}", cross(px(tx(x)), TOP + plot_h - 8.0, series.colour));
            }
            let ly = legend_y();
            let lx = WIDTH - RIGHT + 12.0;
            let _ = writeln!(
                s,
                r#"<line x1="{lx}" y1="{ly}" x2="{}" y2="{ly}" stroke="{}" stroke-width="1.5"{dash}/><text x="{}" y="{}">{}</text>"#,
                lx + 24.0,
                series.colour,
                lx + 30.0,
                ly + 4.0,
                escape(&series.label)
            );
        }
        if any_failed {
            let ly = legend_y();
            let _ = writeln!(
                s,
                r#"{}<text x="{}" y="{}">failed run</text>"#,
                cross(lx + 12.0, ly, "black"),
                lx + 30.0,
                ly + 4.0
            );
        }
        s.push_str("</svg>\n");
        s
    }
}

/// A cross marking a failed run, centred at `(x, y)`.
fn cross(x: f64, y: f64, colour: &str) -> String {
    format!(
        r#"<path class="failed" d="M{:.1},{:.1} l8,8 m0,-8 l-8,8" stroke="{colour}" stroke-width="2"/>"#,
        x - 4.0,
        y - 4.0
    )
}

/// Axis range (in plotted units) with a margin, ending on ticks: whole
/// decades on log axes, multiples of the tick step on linear ones.
fn range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if log {
        let (a, b) = (lo.floor(), hi.ceil());
        (a, if b > a { b } else { a + 1.0 })
    } else {
        let pad = if hi > lo {
            0.05 * (hi - lo)
        } else {
            0.5 * lo.abs().max(1.0)
        };
        // Snapping widens the range, which may call for a longer step.
        let (mut a, mut b) = (lo - pad, hi + pad);
        for _ in 0..4 {
            let step = tick_step(a, b);
            let snapped = ((a / step).floor() * step, (b / step).ceil() * step);
            if tick_step(snapped.0, snapped.1) == step {
                return snapped;
            }
            (a, b) = snapped;
        }
        (a, b)
    }
}

/// A round step (1, 2 or 5 times a power of ten) giving about six ticks.
fn tick_step(lo: f64, hi: f64) -> f64 {
    let raw = (hi - lo) / 6.0;
    let magnitude = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * magnitude)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * magnitude)
}

/// Tick positions (plotted units) and labels: each decade on a log axis,
/// about six round numbers on a linear one.
fn ticks(lo: f64, hi: f64, log: bool) -> Vec<(f64, String)> {
    if log {
        return (lo as i32..=hi as i32)
            .map(|e| (e as f64, format!("1e{e}")))
            .collect();
    }
    let step = tick_step(lo, hi);
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let mut out = Vec::new();
    let mut k = (lo / step).ceil();
    while k * step <= hi + 1e-6 * step {
        let v = k * step;
        out.push((v, format!("{v:.decimals$}")));
        k += 1.0;
    }
    out
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_are_whole_decades() {
        let t = ticks(-3.0, 1.0, true);
        assert_eq!(t.len(), 5);
        assert_eq!(t[0].1, "1e-3");
    }

    #[test]
    fn linear_ticks_are_round_and_inside() {
        let t = ticks(-2.9, -2.1, false);
        assert!(t.iter().all(|(v, _)| *v >= -2.9 && *v <= -2.1));
        assert!(t.len() >= 4, "{t:?}");
        assert_eq!(t[0].1, "-2.8");
    }

    #[test]
    fn a_failed_run_breaks_the_line_and_is_marked() {
        let plot = Plot {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: true,
            log_y: false,
            reference: Some(("FE".into(), -2.76)),
        };
        let svg = plot.svg(&[Series {
            label: "s".into(),
            points: vec![
                (10.0, -2.5),
                (100.0, f64::NAN),
                (1000.0, -2.7),
                (1e4, -2.75),
            ],
            colour: COLOURS[0],
            dashed: false,
        }]);
        assert_eq!(svg.matches("<polyline").count(), 2, "{svg}");
        assert_eq!(svg.matches("<circle").count(), 3);
        // One cross on the axis, one in the legend.
        assert_eq!(svg.matches(r#"class="failed""#).count(), 2);
        assert!(svg.contains(">FE</text>") && svg.contains(">failed run</text>"));
    }

    #[test]
    fn linear_axes_end_on_labelled_ticks() {
        let (lo, hi) = range([-3.1, -2.25].into_iter(), false);
        let t = ticks(lo, hi, false);
        assert!((t[0].0 - lo).abs() < 1e-9, "{t:?} from {lo}");
        assert!((t[t.len() - 1].0 - hi).abs() < 1e-9, "{t:?} to {hi}");
    }

    #[test]
    fn svg_leaves_out_points_a_log_axis_cannot_show() {
        let plot = Plot {
            title: "t".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: true,
            log_y: true,
            reference: None,
        };
        let svg = plot.svg(&[Series {
            label: "a < b".into(),
            points: vec![(1.0, 1.0), (10.0, 0.0), (100.0, 0.01)],
            colour: COLOURS[0],
            dashed: false,
        }]);
        assert_eq!(svg.matches("<circle").count(), 2);
        assert!(svg.contains("a &lt; b"));
    }
}
