//! The log-log SVG plot of `rtow converge` (the `plot` feature: plotters).

use super::ConvergeReport;
use crate::error::{Error, Result};
use plotters::prelude::*;

pub(super) fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let mut out = Vec::new();
    if !(lo > 0.0 && hi >= lo && hi.is_finite()) {
        return out;
    }
    let mut d = lo.log10().floor() as i32;
    while d <= hi.log10().ceil() as i32 {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(d);
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
        d += 1;
    }
    if out.len() < 2 {
        out = vec![lo, hi];
    }
    out
}

/// A tick value with as many decimals as it needs (0.005, 0.02, 1, 20).
pub(super) fn tick_label(v: f64) -> String {
    let decimals = if v > 0.0 { (-v.log10().floor()).max(0.0) as usize } else { 0 };
    format!("{v:.decimals$}")
}

/// The curves' colours, in order (matplotlib's first eight), repeated past eight curves.
const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
];

/// A drawing error, as rtow reports it.
fn plot_err(e: &dyn std::fmt::Display) -> Error {
    Error::Input(format!("plot: {e}"))
}

/// The range an axis shows: from the least to the greatest value `axis`
/// takes of `pts`, widened by a factor of 1.3 either side.
fn axis_range(pts: &[(f64, f64)], axis: fn(&(f64, f64)) -> f64) -> (f64, f64) {
    let bound = |lo: bool| {
        let v = pts.iter().map(axis);
        if lo {
            v.reduce(f64::min).unwrap_or(1.0)
        } else {
            v.reduce(f64::max).unwrap_or(1.0)
        }
    };
    (bound(true) / 1.3, bound(false) * 1.3)
}

impl ConvergeReport {
    /// The log-log plot of RMSE against seconds, as SVG text.
    pub fn svg(&self) -> Result<String> {
        let curves = self.curves();
        let mut pts: Vec<(f64, f64)> = curves.iter().flat_map(|c| c.usable()).collect();
        let empty = pts.is_empty();
        if empty {
            // Nothing to draw (e.g. a scene without noise: every error is 0);
            // still write a plot that says so rather than fail after measuring.
            pts = vec![(1e-3, 1e-3), (1.0, 1.0)];
        }
        let (t0, t1) = axis_range(&pts, |p| p.0);
        let (e0, e1) = axis_range(&pts, |p| p.1);
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (820, 560)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| plot_err(&e))?;
            let mut chart = ChartBuilder::on(&root)
                .caption(self.plot_title(empty), ("sans-serif", 20))
                .margin(12)
                .x_label_area_size(44)
                .y_label_area_size(70)
                .build_cartesian_2d(
                    (t0..t1).log_scale().with_key_points(ticks(t0, t1)),
                    (e0..e1).log_scale().with_key_points(ticks(e0, e1)),
                )
                .map_err(|e| plot_err(&e))?;
            chart
                .configure_mesh()
                .x_desc("render time (s)")
                .y_desc("RMSE vs reference")
                .x_label_formatter(&|v| tick_label(*v))
                .y_label_formatter(&|v| tick_label(*v))
                .draw()
                .map_err(|e| plot_err(&e))?;
            for (i, c) in curves.iter().enumerate() {
                let col = PALETTE[i % PALETTE.len()];
                let p = c.usable();
                chart
                    .draw_series(LineSeries::new(p.clone(), col.stroke_width(2)))
                    .map_err(|e| plot_err(&e))?
                    .label(c.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], col.stroke_width(2)));
                chart.draw_series(p.iter().map(|&q| Circle::new(q, 3, col.filled()))).map_err(|e| plot_err(&e))?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()
                .map_err(|e| plot_err(&e))?;
            root.present().map_err(|e| plot_err(&e))?;
        }
        Ok(svg)
    }

    /// The plot's title: the scene and its size, and whether there was nothing to draw.
    fn plot_title(&self, empty: bool) -> String {
        format!(
            "{} {}x{}: RMSE against render time (log-log){}",
            self.scene,
            self.width,
            self.height,
            if empty { ": no measurement has a positive error" } else { "" }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks() {
        assert_eq!(ticks(0.003, 0.06), vec![0.005, 0.01, 0.02, 0.05]);
        assert_eq!(ticks(0.9, 25.0), vec![1.0, 2.0, 5.0, 10.0, 20.0]);
        assert!(ticks(0.0, 1.0).is_empty());
        assert_eq!(ticks(0.003, 0.0045), vec![0.003, 0.0045]);
        let labels: Vec<String> = [0.005, 0.02, 1.0, 20.0].iter().map(|&v| tick_label(v)).collect();
        assert_eq!(labels, ["0.005", "0.02", "1", "20"]);
    }
}
