//! What `rtow stress` found: tallies per case, gates, checks, and the table.

use std::fmt::Write as _;

/// What one case measured.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tally {
    pub rays: u64,
    /// Wrong decisions outside the rounding band (for spawned rays: rays that
    /// entered the sphere they left and did not reach its far wall).
    pub wrong: u64,
    /// Decisions inside the rounding band (not errors).
    pub in_band: u64,
    /// Wrong front/back face outside the band.
    pub faces: u64,
    /// Spawned rays that left their sphere and hit it again.
    pub rehits: u64,
    /// Non-finite values met (t, hit points, directions, samples).
    pub nan: u64,
    /// Largest distance of a hit point from its sphere, over |r| (decisions outside the band).
    pub max_err_r: f64,
    /// The same for hits inside the rounding band (near tangency).
    pub max_err_r_band: f64,
    /// Largest distance of a hit point from its sphere, over its error bound (must be <= 1).
    pub max_err_bound: f64,
}

impl Tally {
    pub(super) fn err(&mut self, dist: f64, r: f64, bound: Option<f64>, in_band: bool) {
        if in_band {
            self.max_err_r_band = self.max_err_r_band.max(dist / r);
        } else {
            self.max_err_r = self.max_err_r.max(dist / r);
        }
        if let Some(b) = bound {
            self.max_err_bound = self.max_err_bound.max(dist / b);
        }
    }

    fn clean(&self, gate: Gate) -> bool {
        let core = self.faces == 0 && self.rehits == 0 && self.nan == 0 && self.max_err_bound <= 1.0;
        match gate {
            Gate::Full => core && self.wrong == 0,
            Gate::NoLeaks => core,
            Gate::Reference => true,
        }
    }
}

/// What a row must show to pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gate {
    /// Everything: no wrong decision, face, re-hit or NaN, every error within its bound.
    Full,
    /// The same except `wrong` (hit points below f32 resolution, where the
    /// offset exceeds the radius and an entering ray may be pushed through the
    /// sphere: see `geometry::surface`).
    NoLeaks,
    /// The textbook reference: shown, never gating.
    Reference,
}

/// One line of the table.
#[derive(Clone, Debug)]
pub struct StressRow {
    pub section: &'static str,
    pub case: String,
    pub kernel: &'static str,
    pub tally: Tally,
    pub gate: Gate,
}

impl StressRow {
    pub fn ok(&self) -> bool {
        self.tally.clean(self.gate)
    }
}

/// A pass/fail check that is not a row of counts.
#[derive(Clone, Debug)]
pub struct Check {
    pub name: String,
    pub value: f64,
    pub limit: f64,
    pub ok: bool,
    pub note: String,
}

impl Check {
    pub(super) fn at_most(name: impl Into<String>, value: f64, limit: f64, note: impl Into<String>) -> Self {
        Check { name: name.into(), value, limit, ok: value <= limit, note: note.into() }
    }
}

/// The outside sweep by decade of `r / |o - c|`: robust (scalar) and textbook.
#[derive(Clone, Debug, Default)]
pub struct Decade {
    pub ratio_exp: i32,
    pub robust: Tally,
    pub textbook: Tally,
}

/// Re-hits and leaks with another offset rule (scalar, every scatter).
#[derive(Clone, Debug)]
pub struct OffsetScan {
    pub rule: String,
    pub rays: u64,
    pub rehits: u64,
    /// Entering rays that did not reach the far wall.
    pub wrong: u64,
}

#[derive(Clone, Debug)]
pub struct StressReport {
    pub quick: bool,
    pub seed: u64,
    pub isa: &'static str,
    pub rows: Vec<StressRow>,
    pub checks: Vec<Check>,
    pub decades: Vec<Decade>,
    pub offset_scan: Vec<OffsetScan>,
    pub seconds: f64,
}

impl StressReport {
    pub fn passed(&self) -> bool {
        self.rows.iter().all(StressRow::ok) && self.checks.iter().all(|c| c.ok)
    }

    fn failures(&self) -> Vec<String> {
        let mut v: Vec<String> =
            self.rows.iter().filter(|r| !r.ok()).map(|r| format!("{} [{}]", r.case, r.kernel)).collect();
        v.extend(self.checks.iter().filter(|c| !c.ok).map(|c| c.name.clone()));
        v
    }

    /// The tables `rtow stress` prints.
    pub fn table(&self) -> String {
        let mut s = String::new();
        self.write_legend(&mut s);
        self.write_rows(&mut s);
        self.write_decades(&mut s);
        self.write_offset_scan(&mut s);
        self.write_checks(&mut s);
        let f = self.failures();
        if f.is_empty() {
            let _ = writeln!(s, "\nall bounds hold");
        } else {
            let _ = writeln!(s, "\nBROKEN: {}", f.join(", "));
        }
        s
    }

    /// The run's first line (seed, SIMD, time) and what the rows' columns mean.
    fn write_legend(&self, s: &mut String) {
        let _ = writeln!(
            s,
            "rtow stress{}: seed {}, SIMD {}, {:.1} s",
            if self.quick { " --quick" } else { "" },
            self.seed,
            self.isa,
            self.seconds
        );
        let _ = writeln!(
            s,
            "wrong = wrong decisions outside the rounding band (spawned rays: entering rays that did not reach\n\
             the far wall); band = decisions inside it (not errors); faces = wrong front/back; err/r = largest\n\
             distance of a hit point from its sphere over |r|, outside / inside the band; err/bound = the same\n\
             over its error bound (must be <= 1); re-hits = spawned rays leaving a sphere that hit it again;\n\
             NaN = non-finite values met. Below f32 resolution: hit points where the offset exceeds |r|\n\
             (|p|_inf > ~1e6 |r|), where entering rays may be pushed through the sphere: wrong does not gate."
        );
    }

    /// The rows, a table per section, each under its header.
    fn write_rows(&self, s: &mut String) {
        let mut section = "";
        for r in &self.rows {
            if r.section != section {
                section = r.section;
                let _ = writeln!(
                    s,
                    "\n{:<44} {:<8} {:>8} {:>6} {:>6} {:>5} {:>8} {:>8} {:>9} {:>7} {:>4}  ok",
                    section,
                    "kernel",
                    "rays",
                    "wrong",
                    "band",
                    "faces",
                    "err/r",
                    "(band)",
                    "err/bound",
                    "re-hits",
                    "NaN"
                );
            }
            let t = &r.tally;
            let bound = if r.gate != Gate::Reference { format!("{:.3}", t.max_err_bound) } else { "-".into() };
            let _ = writeln!(
                s,
                "{:<44} {:<8} {:>8} {:>6} {:>6} {:>5} {:>8.1e} {:>8.1e} {:>9} {:>7} {:>4}  {}",
                r.case,
                r.kernel,
                t.rays,
                t.wrong,
                t.in_band,
                t.faces,
                t.max_err_r,
                t.max_err_r_band,
                bound,
                t.rehits,
                t.nan,
                match (r.gate, r.ok()) {
                    (Gate::Reference, _) => "ref",
                    (_, true) => "ok",
                    _ => "FAIL",
                }
            );
        }
    }

    /// The outside sweep by decade of `r / |o - c|`, robust against textbook (if measured).
    fn write_decades(&self, s: &mut String) {
        if self.decades.is_empty() {
            return;
        }
        let _ = writeln!(
            s,
            "\noutside sweep by r/|o-c| (scalar robust vs textbook b*b-4ac, t_min = 0.001)\n\
             {:<12} {:>8} {:>14} {:>12} {:>16} {:>14}",
            "r/|o-c|", "rays", "robust wrong", "robust err/r", "textbook wrong", "textbook err/r"
        );
        for d in &self.decades {
            let _ = writeln!(
                s,
                "1e{:<3}..1e{:<3} {:>8} {:>14} {:>12.2e} {:>16} {:>14.2e}",
                d.ratio_exp,
                d.ratio_exp + 1,
                d.robust.rays,
                d.robust.wrong,
                d.robust.max_err_r,
                d.textbook.wrong,
                d.textbook.max_err_r
            );
        }
    }

    /// Re-hits and leaks under each other offset rule (if scanned).
    fn write_offset_scan(&self, s: &mut String) {
        if self.offset_scan.is_empty() {
            return;
        }
        let _ = writeln!(
            s,
            "\noffset rules (self-intersection sweep, scalar, every scatter, resolvable hit points; u = 2^-24)\n{:<36} {:>9} {:>8} {:>7}",
            "offset", "rays", "re-hits", "wrong"
        );
        for o in &self.offset_scan {
            let _ = writeln!(s, "{:<36} {:>9} {:>8} {:>7}", o.rule, o.rays, o.rehits, o.wrong);
        }
    }

    /// The checks that are not rows of counts, each with its value, limit and note.
    fn write_checks(&self, s: &mut String) {
        let _ = writeln!(s, "\nchecks");
        for c in &self.checks {
            let _ = writeln!(
                s,
                "  {:<4} {:<66} {:>8.4} <= {:<3} {}",
                if c.ok { "ok" } else { "FAIL" },
                c.name,
                c.value,
                c.limit,
                c.note
            );
        }
    }
}
