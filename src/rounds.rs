//! A render in rounds of samples: how `--time-limit`, `--preview-every` and a
//! graceful stop on SIGINT work.
//!
//! After each round every pixel holds the same sample indices, so the tiles
//! are exactly the render of that many samples per pixel (the film's sums are
//! exact, [`crate::film::accum`]): an image stopped after `k` samples is bit
//! for bit `rtow render --spp k`'s, and its film resumes to any larger count.
//! A round, once started, is finished: the budget and a signal are looked at
//! between rounds, and rounds are sized to fit: the first is one sample per
//! pixel (it measures the rate), each next one as many samples as fit in its
//! target time, which grows with the render (a quarter of the time so far,
//! between [`MIN_ROUND`] and [`MAX_ROUND`]), is at most the preview interval,
//! and never more than what is left of the time limit by the last round's
//! rate. So a time limit is overrun only by the error of that prediction (a
//! round's rate is steady: every round covers the whole image), and a signal
//! waits at most one round (at most [`MAX_ROUND`] once the first is done).

use crate::error::Result;
use crate::film::TileFilm;
use serde::Serialize;
use std::time::{Duration, Instant};

/// A render cut into rounds of samples (this module): after each round
/// every pixel holds the same sample indices, so the tiles are exactly the
/// render of that many samples ([`crate::film`]: the sums are exact).
pub(crate) trait Rounds {
    /// The end of the next round's sample indices, given the samples done
    /// (`done..end` is what is left); `None` stops. Never more than `end`.
    fn next(&mut self, done: u32, end: u32) -> Option<u32>;
    /// A round ended: the tiles hold every sample below `done`; the round
    /// took `seconds`. An error stops the render.
    fn ended(&mut self, tiles: &[TileFilm], done: u32, seconds: f64) -> Result<()>;
}

/// A round's shortest target time.
pub const MIN_ROUND: Duration = Duration::from_millis(500);
/// A round's longest target time: how long a signal waits at most (after the first round).
pub const MAX_ROUND: Duration = Duration::from_secs(20);

/// Why a render in rounds stopped before its last sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stopped {
    /// The next round would not have fit in `--time-limit`.
    TimeLimit,
    /// SIGINT, SIGTERM or SIGHUP asked the run to stop.
    Signal,
}

/// What a render in rounds did: rounds, where it stopped and why.
#[derive(Clone, Debug, Serialize)]
pub struct RoundsReport {
    pub rounds: u32,
    /// The samples per pixel the run was asked for.
    pub spp_requested: u32,
    /// `None`: every requested sample was rendered.
    pub stopped: Option<Stopped>,
    /// The signal's name when `stopped` is `signal`.
    pub signal: Option<&'static str>,
    /// The number of the signal (the run exits with 128 + it).
    #[serde(skip)]
    pub signal_number: i32,
    /// Previews written.
    pub previews: u32,
    /// The film written when a signal stopped the render.
    pub film: Option<std::path::PathBuf>,
}

/// A preview of the image so far: called with the tiles after a round.
pub type Preview<'a> = &'a mut (dyn FnMut(&[TileFilm]) -> Result<()> + Send);

/// Decides the rounds of a render (see the module documentation).
pub(crate) struct Schedule<'a> {
    start: Instant,
    deadline: Option<Instant>,
    /// The preview and its interval.
    preview: Option<(Duration, Preview<'a>)>,
    last_preview: Option<Instant>,
    /// Whether a signal stops the render between rounds.
    on_signal: bool,
    /// Seconds per sample per pixel, measured by the last round.
    rate: Option<f64>,
    begun: u32,
    report: RoundsReport,
}

impl<'a> Schedule<'a> {
    /// Rounds up to `spp_requested` samples within `time_limit` (from now),
    /// `preview` after the first round and then once its interval has
    /// passed, stopping between rounds on a signal recorded by
    /// [`crate::output::Graceful`] when `on_signal`.
    pub fn new(
        spp_requested: u32,
        time_limit: Option<Duration>,
        preview: Option<(Duration, Preview<'a>)>,
        on_signal: bool,
    ) -> Schedule<'a> {
        let start = Instant::now();
        Schedule {
            start,
            deadline: time_limit.map(|t| start + t),
            preview,
            last_preview: None,
            on_signal,
            rate: None,
            begun: 0,
            report: RoundsReport {
                rounds: 0,
                spp_requested,
                stopped: None,
                signal: None,
                signal_number: 0,
                previews: 0,
                film: None,
            },
        }
    }

    pub fn report(&self) -> RoundsReport {
        self.report.clone()
    }

    /// The target time of the next round.
    fn target(&self, now: Instant) -> Duration {
        let t = (now - self.start).div_f64(4.0).clamp(MIN_ROUND, MAX_ROUND);
        self.preview.as_ref().map_or(t, |&(every, _)| t.min(every))
    }

    fn stop(&mut self, why: Stopped) -> Option<u32> {
        self.report.stopped = Some(why);
        None
    }
}

impl Rounds for Schedule<'_> {
    fn next(&mut self, done: u32, end: u32) -> Option<u32> {
        if done >= end {
            return None;
        }
        if self.on_signal {
            if let Some((name, number)) = crate::output::stop_signal() {
                self.report.signal = Some(name);
                self.report.signal_number = number;
                return self.stop(Stopped::Signal);
            }
        }
        self.begun = done;
        let Some(rate) = self.rate else { return Some(done + 1) };
        let now = Instant::now();
        let fit = |d: Duration| (d.as_secs_f64() / rate.max(1e-12)).floor().min(u32::MAX as f64) as u32;
        let mut n = fit(self.target(now)).max(1);
        if let Some(deadline) = self.deadline {
            let left = fit(deadline.saturating_duration_since(now));
            if left == 0 {
                return self.stop(Stopped::TimeLimit);
            }
            n = n.min(left);
        }
        Some(done + n.min(end - done))
    }

    fn ended(&mut self, tiles: &[TileFilm], done: u32, seconds: f64) -> Result<()> {
        self.report.rounds += 1;
        self.rate = Some(seconds / (done - self.begun).max(1) as f64);
        let Some((every, preview)) = self.preview.as_mut() else { return Ok(()) };
        let now = Instant::now();
        if self.last_preview.is_none_or(|t| now - t >= *every) {
            preview(tiles)?;
            self.report.previews += 1;
            self.last_preview = Some(Instant::now());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_round_is_one_sample_and_the_next_fit_their_time() {
        let mut s = Schedule::new(1000, None, None, false);
        assert_eq!(s.next(0, 1000), Some(1));
        s.ended(&[], 1, 0.01).unwrap();
        // Target MIN_ROUND (0.5 s) at 0.01 s a sample: 50 samples.
        assert_eq!(s.next(1, 1000), Some(51));
        s.ended(&[], 51, 0.5).unwrap();
        assert_eq!(s.next(999, 1000), Some(1000), "never past the end");
        assert_eq!(s.next(1000, 1000), None);
        assert_eq!(s.report().stopped, None);
        assert_eq!(s.report().rounds, 2);
    }

    #[test]
    fn a_time_limit_stops_before_a_round_that_would_not_fit() {
        let mut s = Schedule::new(1000, Some(Duration::from_millis(50)), None, false);
        assert_eq!(s.next(0, 1000), Some(1), "one round always");
        // One sample took 10 s: nothing more fits in what is left of 50 ms.
        s.ended(&[], 1, 10.0).unwrap();
        assert_eq!(s.next(1, 1000), None);
        assert_eq!(s.report().stopped, Some(Stopped::TimeLimit));
    }

    #[test]
    fn previews_come_after_the_first_round_then_by_the_interval() {
        let mut calls = 0;
        let mut record = |_: &[TileFilm]| {
            calls += 1;
            Ok(())
        };
        let mut s = Schedule::new(10, None, Some((Duration::from_secs(3600), &mut record)), false);
        for k in 0..3 {
            let end = s.next(k, 10).unwrap();
            s.ended(&[], end, 1e-3).unwrap();
            assert_eq!(s.report().previews, 1, "right after the first round, then not within the hour");
        }
        drop(s);
        assert_eq!(calls, 1);
    }
}
