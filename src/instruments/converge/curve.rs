//! Error against cost curves (log-log interpolation) and their comparison at
//! equal time and equal error.

#[derive(Clone, Debug)]
pub struct Curve {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

fn lerp_log(x: f64, (x0, y0): (f64, f64), (x1, y1): (f64, f64)) -> f64 {
    let (lx, lx0, lx1) = (x.ln(), x0.ln(), x1.ln());
    if lx1 == lx0 {
        return y0.min(y1);
    }
    let f = (lx - lx0) / (lx1 - lx0);
    (y0.ln() + f * (y1.ln() - y0.ln())).exp()
}

impl Curve {
    pub(super) fn usable(&self) -> Vec<(f64, f64)> {
        self.points.iter().copied().filter(|&(t, e)| t > 0.0 && e > 0.0 && t.is_finite() && e.is_finite()).collect()
    }

    /// RMSE at `t` seconds, interpolated in log-log between the two measured
    /// times around it (the points sorted by time); `None` outside the range.
    pub fn error_at(&self, t: f64) -> Option<f64> {
        let mut p = self.usable();
        p.sort_by(|a, b| a.0.total_cmp(&b.0));
        p.windows(2)
            .find(|w| w[0].0 <= t && t <= w[1].0)
            .map(|w| lerp_log(t, w[0], w[1]))
            .or_else(|| p.iter().find(|q| q.0 == t).map(|q| q.1))
    }

    /// Seconds to reach RMSE `e`: the first segment, in sample-count order,
    /// whose errors bracket `e`, interpolated in log-log; `None` if never reached.
    pub fn time_at(&self, e: f64) -> Option<f64> {
        let p = self.usable();
        if let Some(q) = p.iter().find(|q| q.1 == e) {
            return Some(q.0);
        }
        p.windows(2)
            .find(|w| (w[0].1 - e) * (w[1].1 - e) < 0.0)
            .map(|w| lerp_log(e, (w[0].1, w[0].0), (w[1].1, w[1].0)))
    }

    fn time_range(&self) -> Option<(f64, f64)> {
        let p = self.usable();
        let lo = p.iter().map(|q| q.0).reduce(f64::min)?;
        let hi = p.iter().map(|q| q.0).reduce(f64::max)?;
        Some((lo, hi))
    }

    fn min_error(&self) -> Option<f64> {
        self.usable().iter().map(|q| q.1).reduce(f64::min)
    }
}

/// What a curve's horizontal axis measures. Seconds are what a user waits,
/// but on a shared machine they are noisy; rays are exact and repeatable (and
/// ignore differences in the cost of a ray, e.g. between kernels).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Cost {
    Seconds,
    Rays,
}

/// How `other` compares to `base`.
#[derive(Clone, Debug, PartialEq)]
pub struct CurveComparison {
    pub base: String,
    pub other: String,
    /// (RMSE level, base seconds / other seconds) at the lowest error both reach.
    pub equal_error: Option<(f64, f64)>,
    /// (seconds, base MSE / other MSE) at the longest time both cover: the
    /// speedup if both errors fall as 1/time.
    pub equal_time: Option<(f64, f64)>,
}

/// Compares two curves (see [`CurveComparison`]).
pub fn compare(base: &Curve, other: &Curve) -> CurveComparison {
    let equal_error = match (base.min_error(), other.min_error()) {
        (Some(a), Some(b)) => {
            let e = a.max(b);
            match (base.time_at(e), other.time_at(e)) {
                (Some(tb), Some(to)) if to > 0.0 => Some((e, tb / to)),
                _ => None,
            }
        }
        _ => None,
    };
    let equal_time = match (base.time_range(), other.time_range()) {
        (Some((lb, hb)), Some((lo, ho))) if lb.max(lo) <= hb.min(ho) => {
            let t = hb.min(ho);
            match (base.error_at(t), other.error_at(t)) {
                (Some(eb), Some(eo)) if eo > 0.0 => Some((t, (eb * eb) / (eo * eo))),
                _ => None,
            }
        }
        _ => None,
    };
    CurveComparison { base: base.label.clone(), other: other.label.clone(), equal_error, equal_time }
}
