//! The outputs of `rtow converge`: CSV, markdown, the comparison lines, files.

use super::curve::{compare, Cost, Curve, CurveComparison};
use super::split::comparison_markdown;
use super::ConvergeReport;
use crate::choice::KernelChoice;
use crate::error::{Error, Result};
use crate::output::{OutputId, Outputs};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

impl ConvergeReport {
    /// One curve per (kernel, variant), in the order measured.
    pub fn curves(&self) -> Vec<Curve> {
        self.curves_by(Cost::Seconds)
    }

    /// One curve per (kernel, variant) with `cost` on the horizontal axis.
    pub fn curves_by(&self, cost: Cost) -> Vec<Curve> {
        let mut out: Vec<Curve> = Vec::new();
        for r in &self.rows {
            let label = r.label();
            let x = match cost {
                Cost::Seconds => r.seconds,
                Cost::Rays => r.rays as f64,
            };
            match out.iter_mut().find(|c| c.label == label) {
                Some(c) => c.points.push((x, r.rmse)),
                None => out.push(Curve { label, points: vec![(x, r.rmse)] }),
            }
        }
        out
    }

    /// Every configuration against the first one, and, for every other kernel,
    /// its variants against its own first variant.
    pub fn comparisons(&self) -> Vec<CurveComparison> {
        self.comparisons_by(Cost::Seconds)
    }

    /// [`ConvergeReport::comparisons`] with `cost` in place of seconds.
    pub fn comparisons_by(&self, cost: Cost) -> Vec<CurveComparison> {
        let curves = self.curves_by(cost);
        let mut out = Vec::new();
        let Some(first) = curves.first() else {
            return out;
        };
        for c in &curves[1..] {
            out.push(compare(first, c));
        }
        let mut kernels: Vec<KernelChoice> = Vec::new();
        for r in &self.rows {
            if !kernels.contains(&r.kernel) {
                kernels.push(r.kernel);
            }
        }
        for k in kernels.iter().skip(1) {
            let prefix = format!("{}/", k.name());
            let own: Vec<&Curve> = curves.iter().filter(|c| c.label.starts_with(&prefix)).collect();
            for c in own.iter().skip(1) {
                out.push(compare(own[0], c));
            }
        }
        out
    }

    pub fn csv(&self) -> String {
        let mut s = String::from(
            "scene,width,height,kernel,variant,spp,seconds,rays,samples,mrays_per_s,rmse,relmse,mean_rel_error,efficiency,image_hash\n",
        );
        for r in &self.rows {
            let _ = writeln!(
                s,
                "{},{},{},{},{},{},{:.6},{},{},{:.4},{:.6e},{:.6e},{:.6e},{:.6e},{}",
                self.scene,
                self.width,
                self.height,
                r.kernel.name(),
                r.variant.name(),
                r.spp,
                r.seconds,
                r.rays,
                r.samples,
                r.rays as f64 / r.seconds / 1e6,
                r.rmse,
                r.relmse,
                r.mean_rel_error,
                r.efficiency(),
                r.image_hash
            );
        }
        s
    }

    /// Lines describing the comparisons, for the terminal and the markdown file.
    pub fn comparison_lines(&self) -> Vec<String> {
        let by_rays = self.comparisons_by(Cost::Rays);
        self.comparisons()
            .iter()
            .zip(&by_rays)
            .map(|(c, r)| {
                let ee = match c.equal_error {
                    Some((e, x)) => format!("equal error (RMSE {e:.4}): {x:.2}x in time"),
                    None => "equal error: curves do not overlap in time".into(),
                };
                let er = match r.equal_error {
                    Some((e, x)) => format!("{x:.2}x in rays (RMSE {e:.4})"),
                    None => "curves do not overlap in rays".into(),
                };
                let et = match c.equal_time {
                    Some((t, x)) => format!("equal time ({t:.3} s): MSE ratio {x:.2}x"),
                    None => "equal time: time ranges do not overlap".into(),
                };
                format!("{} vs {}: {ee}, {er}; {et}", c.other, c.base)
            })
            .collect()
    }

    /// With `at_spp` set: what every other configuration needs to reach the
    /// RMSE that the baseline (the first configuration) measured at `at_spp`.
    pub fn reach_lines(&self) -> Vec<String> {
        let Some(n) = self.at_spp else {
            return vec![];
        };
        let (by_time, by_rays) = (self.curves(), self.curves_by(Cost::Rays));
        let Some(base) = by_time.first() else {
            return vec![];
        };
        let Some(b) = self.rows.iter().find(|r| r.label() == base.label && r.spp == n) else {
            return vec![];
        };
        let mut out = vec![format!(
            "to reach the RMSE of {} at {n} spp ({:.5}, {:.3} s, {:.2}M rays):",
            b.label(),
            b.rmse,
            b.seconds,
            b.rays as f64 / 1e6
        )];
        for (ct, cr) in by_time.iter().zip(&by_rays).skip(1) {
            out.push(match (ct.time_at(b.rmse), cr.time_at(b.rmse)) {
                (Some(t), Some(r)) => format!(
                    "  {}: {t:.3} s ({:.2}x the time), {:.2}M rays ({:.2}x the rays)",
                    ct.label,
                    t / b.seconds,
                    r / 1e6,
                    r / b.rays as f64
                ),
                _ => format!("  {}: does not reach it at the measured sample counts", ct.label),
            });
        }
        out
    }

    /// Kernels that rendered the same variant and spp to different images
    /// (they must not: both kernels are one estimator).
    pub fn kernel_mismatches(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (i, a) in self.rows.iter().enumerate() {
            for b in &self.rows[i + 1..] {
                if a.kernel != b.kernel && a.variant == b.variant && a.spp == b.spp && a.image_hash != b.image_hash {
                    out.push(format!("{} and {} differ at {} spp ({})", a.label(), b.label(), a.spp, a.variant.name()));
                }
            }
        }
        out
    }

    pub fn markdown(&self) -> String {
        let mut s = format!(
            "# Run time against error: {} ({}x{}, depth {}, seed {})\n\nReference: {}. Seconds: wall time of the render \
             (scene preparation apart), the fastest of {} run(s), {} thread(s). Error against the reference: RMSE and relMSE \
             of the linear image; mean signed rel. error = mean of (x - r) / (r + 0.01), zero in expectation without bias.\n\n",
            self.scene, self.width, self.height, self.max_depth, self.seed, self.reference, self.repeat, self.threads
        );
        if let Some(n) = &self.reference_noise {
            let _ = writeln!(
                s,
                "Reference noise: its own MSE, estimated from its two halves, is {:.3e}, {:.1}% of the smallest MSE \
                 measured ({:.3e}); every MSE below carries it.{}\n",
                n.mse,
                100.0 * n.share(),
                n.smallest_mse,
                if n.warning().is_some() { " **Too noisy for these errors: raise --reference-spp.**" } else { "" }
            );
        }
        s += "| kernel | variant | spp | seconds | Mrays/s | samples/px | RMSE | relMSE | mean signed rel. error | efficiency 1/(MSE s) |\n";
        s += "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
        let px = (self.width as f64 * self.height as f64).max(1.0);
        for r in &self.rows {
            let _ = writeln!(s, "| {} |", r.cells(px).join(" | "));
        }
        let reach = self.reach_lines();
        if let Some((head, rest)) = reach.split_first() {
            let _ = writeln!(s, "\n{}\n", head.replace("to reach", "To reach"));
            for l in rest {
                let _ = writeln!(s, "- {}", l.trim_start());
            }
        }
        let lines = self.comparison_lines();
        if !lines.is_empty() {
            s +=
                "\nSpeedups (log-log interpolation between measured sample counts; in rays: the same with rays traced \
                  in place of seconds):\n\n";
            for l in lines {
                let _ = writeln!(s, "- {l}");
            }
        }
        if let Some(first) = self.splits.first() {
            let _ = write!(
                s,
                "\n## Where the error lives: {} spp, {} seeds\n\nEach variant rendered {} times at {} spp with \
                 independent seeds by the scalar kernel, every term of every pixel added into its bucket: path length \
                 (segments from the camera to the light or background) and strategy. Variance: across the seeds, of \
                 a bucket's pixel values, averaged over pixels and channels; the image's is its MSE at {} spp. \
                 Covariance: what the buckets leave of the MSE. MSE x s: times the variant's measured seconds.\n\n",
                first.spp, first.seeds, first.seeds, first.spp, first.spp
            );
            s += "MSE x seconds by path length (lower is faster to a given error):\n\n";
            s += &comparison_markdown(&self.splits);
            for sp in &self.splits {
                s += "\n";
                s += &sp.markdown();
            }
        }
        s
    }

    /// The splits' buckets as CSV (`<scene>-split.csv`).
    pub fn split_csv(&self) -> String {
        let mut s = String::from("scene,variant,spp,seeds,length,strategy,mean,variance,mse_seconds,seconds\n");
        for sp in &self.splits {
            sp.csv_rows(&self.scene, &mut s);
        }
        s
    }
    /// The run's description beside its tables: what was measured, the
    /// files, and the provenance (docs/figures.md).
    pub fn json(&self, files: &[String]) -> String {
        let v = serde_json::json!({
            "schema": "rtow-converge/1",
            "scene": self.scene,
            "width": self.width,
            "height": self.height,
            "max_depth": self.max_depth,
            "seed": self.seed,
            "reference": self.reference,
            "reference_noise": self.reference_noise,
            "repeat": self.repeat,
            "threads": self.threads,
            "at_spp": self.at_spp,
            "files": files,
            "provenance": self.provenance,
        });
        serde_json::to_string_pretty(&v).expect("serializes") + "\n"
    }

    /// Writes the report into the files checked by [`ReportFiles::check`]:
    /// `<scene>.csv`, `<scene>.md`, (with the `plot` feature) `<scene>.svg`,
    /// `<scene>.json`, with a split `<scene>-split.csv` and, if the run
    /// rendered its reference, `<scene>-reference.exr`; all of them or none.
    /// Returns their paths.
    pub fn write(&self, mut files: ReportFiles) -> Result<Vec<PathBuf>> {
        #[cfg(feature = "plot")]
        let svg = Some(self.svg()?);
        #[cfg(not(feature = "plot"))]
        let svg: Option<String> = None;
        let names: Vec<String> = files
            .slots
            .iter()
            .filter(|s| matches!(s.kind, Kind::Csv | Kind::Markdown | Kind::Svg | Kind::SplitCsv))
            .map(|s| file_name(&s.path))
            .collect();
        for i in 0..files.slots.len() {
            let (kind, id) = (files.slots[i].kind, files.slots[i].id);
            let bytes = match kind {
                Kind::Csv => self.csv().into_bytes(),
                Kind::Markdown => self.markdown().into_bytes(),
                Kind::Svg => svg.clone().unwrap_or_default().into_bytes(),
                Kind::Json => self.json(&names).into_bytes(),
                Kind::SplitCsv => self.split_csv().into_bytes(),
                Kind::Reference => match &self.rendered_reference {
                    Some(img) => img.file_bytes(&files.slots[i].path, 1.0, "reference")?,
                    None => return Err(Error::Input("the run rendered no reference to write (internal error)".into())),
                },
            };
            files.outputs.stage(id, &bytes)?;
        }
        let paths = files.slots.iter().map(|s| s.path.clone()).collect();
        let outputs = std::mem::take(&mut files.outputs);
        outputs.commit()?;
        files.created_dir = None;
        Ok(paths)
    }
}

fn file_name(p: &Path) -> String {
    p.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Csv,
    Markdown,
    Svg,
    Json,
    Reference,
    SplitCsv,
}

struct Slot {
    kind: Kind,
    path: PathBuf,
    id: OutputId,
}

/// The files of a `converge` run, checked before any rendering (see
/// [`crate::output`]): none may be an input of the run, each must be
/// writable, and no other run may be writing them. The folder is created if
/// it is missing (its parent must exist), and removed again if the run ends
/// without writing.
pub struct ReportFiles {
    outputs: Outputs,
    slots: Vec<Slot>,
    created_dir: Option<PathBuf>,
}

impl ReportFiles {
    /// Checks the files that a run on scene `scene` writes into `dir`
    /// (`with_reference`: the run renders its reference, and writes it;
    /// `with_split`: it splits the error, `<scene>-split.csv`); `inputs` are
    /// the run's input files with what they are.
    pub fn check(
        dir: &Path,
        scene: &str,
        with_reference: bool,
        with_split: bool,
        inputs: &[(&Path, &str)],
    ) -> Result<ReportFiles> {
        let out_err = |m: String| Error::Output { path: dir.to_path_buf(), message: m };
        let mut created_dir = None;
        if !dir.exists() {
            let parent = match dir.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            if !parent.exists() {
                return Err(out_err(format!("--out: folder {} does not exist", parent.display())));
            }
            if !parent.is_dir() {
                return Err(out_err(format!("--out: {} is not a folder", parent.display())));
            }
            std::fs::create_dir(dir).map_err(|e| out_err(format!("--out: {e}")))?;
            created_dir = Some(dir.to_path_buf());
        } else if !dir.is_dir() {
            return Err(out_err("--out must be a folder".into()));
        }
        let mut files = ReportFiles { outputs: Outputs::new(), slots: Vec::new(), created_dir };
        for (path, what) in inputs {
            files.outputs.input(path, what);
        }
        let stem: String =
            scene.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect();
        let mut kinds = vec![(Kind::Csv, "csv"), (Kind::Markdown, "md")];
        if cfg!(feature = "plot") {
            kinds.push((Kind::Svg, "svg"));
        }
        kinds.push((Kind::Json, "json"));
        if with_split {
            kinds.push((Kind::SplitCsv, "split.csv"));
        }
        for (kind, ext) in kinds {
            let sep = if kind == Kind::SplitCsv { "-" } else { "." };
            let path = dir.join(format!("{stem}{sep}{ext}"));
            let id = files.outputs.add(&path, "--out")?;
            files.slots.push(Slot { kind, path, id });
        }
        if with_reference {
            let path = dir.join(format!("{stem}-reference.exr"));
            let id = files.outputs.add(&path, "--out")?;
            files.slots.push(Slot { kind: Kind::Reference, path, id });
        }
        Ok(files)
    }
}

impl Drop for ReportFiles {
    fn drop(&mut self) {
        // Staged files and locks go first (dropping the outputs), then the
        // folder this run made, if it is still empty.
        drop(std::mem::take(&mut self.outputs));
        if let Some(d) = self.created_dir.take() {
            let _ = std::fs::remove_dir(d);
        }
    }
}
