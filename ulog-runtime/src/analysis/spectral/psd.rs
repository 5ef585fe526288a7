//! Welch's power spectral density of one signal, as it streams.

use super::fft::{Complex, RealFft};
use super::{Interval, breaks_run, hann_periodic};

/// Most segments averaged: enough for a smooth estimate, and a bound on the work.
const MAX_SEGMENTS: usize = 4096;

/// Welch's estimate, as scipy's `welch(x, fs, window='hann', nperseg, noverlap=nperseg/2,
/// detrend='constant', scaling='density')` computes it, over the contiguous runs of a
/// signal (a gap of more than 3 sampling intervals ends a run), each run's segments
/// averaged together: `nperseg` the power of two nearest `fs / 2 Hz` (2 Hz resolution),
/// within 256 and 8192 samples; the sampling rate the median of the first intervals.
#[derive(Debug, Clone, Default)]
pub(crate) struct Welch {
    interval: Interval,
    last: Option<u64>,
    state: Option<State>,
    /// Samples before the rate is known.
    early: Vec<(u64, f64)>,
}

#[derive(Debug, Clone)]
struct State {
    dt_us: u64,
    fft: RealFft,
    window: Vec<f64>,
    /// `1 / (fs Σ w²)`: the density's scale.
    scale: f64,
    /// The current run's samples not yet past a segment start.
    run: Vec<f64>,
    sum: Vec<f64>,
    segments: usize,
    /// A segment, detrended and windowed, and its transform.
    tapered: Vec<f64>,
    spectrum: Vec<Complex>,
}

/// A power spectral density: frequencies and densities (units² per Hz).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Spectrum {
    pub(crate) sample_rate_hz: f64,
    pub(crate) segments: usize,
    pub(crate) freq_hz: Vec<f64>,
    pub(crate) density: Vec<f64>,
}

impl Welch {
    /// Takes one sample; `keep` false ends the current run (the vehicle not in flight).
    #[inline]
    pub(crate) fn push(&mut self, t: u64, x: f64, keep: bool) {
        match &self.state {
            // Enough segments: the rest of the signal changes nothing.
            Some(s) if s.segments >= MAX_SEGMENTS => return,
            Some(_) => {}
            None => {
                if !self.start(t, x, keep) {
                    return;
                }
            }
        }
        self.take(t, x, keep);
    }

    /// A sample at `t` out of flight, its value not read: [`Welch::push`] with `keep` false
    /// (which never uses the value).
    #[inline]
    pub(crate) fn skip(&mut self, t: u64) {
        self.push(t, f64::NAN, false);
    }

    /// Before the rate is known: keeps the sample, until its time gives the rate, then
    /// takes the samples kept. Returns whether the state is made.
    #[cold]
    fn start(&mut self, t: u64, x: f64, keep: bool) -> bool {
        match self.interval.see(t) {
            None => {
                if keep && x.is_finite() {
                    self.early.push((t, x));
                } else {
                    // The run ends here, as `take` ends it.
                    self.early.clear();
                }
                false
            }
            Some(dt) => {
                self.state = Some(State::new(dt));
                for (t, x) in std::mem::take(&mut self.early) {
                    self.take(t, x, true);
                }
                true
            }
        }
    }

    #[inline]
    fn take(&mut self, t: u64, x: f64, keep: bool) {
        let state = self.state.as_mut().expect("made");
        if state.segments >= MAX_SEGMENTS {
            return;
        }
        let gap = self.last.is_some_and(|l| breaks_run(l, t, state.dt_us));
        if !keep || !x.is_finite() || gap {
            state.run.clear();
        }
        self.last = Some(t);
        if keep && x.is_finite() {
            state.push(x);
        }
    }

    /// Whether an estimate is made (a segment seen): [`Welch::finish`] gives one.
    pub(crate) fn has_estimate(&self) -> bool {
        self.state.as_ref().is_some_and(|s| s.segments > 0)
    }

    /// The estimate, if at least one segment was seen.
    pub(crate) fn finish(self) -> Option<Spectrum> {
        let s = self.state?;
        if s.segments == 0 {
            return None;
        }
        let n = s.fft.len();
        let fs = 1e6 / s.dt_us as f64;
        Some(Spectrum {
            sample_rate_hz: fs,
            segments: s.segments,
            freq_hz: (0..=n / 2).map(|k| k as f64 * fs / n as f64).collect(),
            density: s.sum.iter().map(|p| p / s.segments as f64).collect(),
        })
    }
}

impl State {
    fn new(dt_us: u64) -> State {
        let fs = 1e6 / dt_us as f64;
        let n = 2f64
            .powf((fs / 2.0).max(1.0).log2().round())
            .clamp(256.0, 8192.0) as usize;
        let window = hann_periodic(n);
        State {
            dt_us,
            fft: RealFft::new(n),
            scale: 1.0 / (fs * window.iter().map(|w| w * w).sum::<f64>()),
            window,
            run: Vec::with_capacity(2 * n),
            sum: vec![0.0; n / 2 + 1],
            segments: 0,
            tapered: vec![0.0; n],
            spectrum: vec![Complex::default(); n / 2 + 1],
        }
    }

    fn push(&mut self, x: f64) {
        self.run.push(x);
        let n = self.fft.len();
        if self.run.len() < n {
            return;
        }
        if self.segments < MAX_SEGMENTS {
            self.segment();
        }
        self.run.drain(..n / 2);
    }

    fn segment(&mut self) {
        let n = self.fft.len();
        let seg = &self.run[..n];
        let mean = seg.iter().sum::<f64>() / n as f64;
        for ((t, x), w) in self.tapered.iter_mut().zip(seg).zip(&self.window) {
            *t = (x - mean) * w;
        }
        self.fft.forward(&self.tapered, &mut self.spectrum);
        for (k, (p, c)) in self.sum.iter_mut().zip(&self.spectrum).enumerate() {
            let one_sided = if k == 0 || k == n / 2 { 1.0 } else { 2.0 };
            *p += c.norm_sqr() * self.scale * one_sided;
        }
        self.segments += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timestamps_jumping_by_7e18_us_give_no_estimate_and_no_overflow() {
        let mut w = Welch::default();
        for i in 0..2_000u64 {
            let t = if i % 2 == 1 {
                7_000_000_000_000_000_000 + i
            } else {
                i
            };
            w.push(t, (i % 5) as f64, true);
        }
        assert!(w.finish().is_none());
    }

    /// A sample skipped out of flight is one pushed with `keep` false, whatever its value:
    /// before the rate is known (the 65th sample gives it, out of flight here) and after,
    /// stretches of one, two and 300 samples. Skipping them cuts the runs: feeding only the
    /// samples in flight (joined across the short stretches) gives another estimate.
    #[test]
    fn a_skipped_sample_is_a_sample_pushed_out_of_flight() {
        let out = |i: u64| {
            i == 64 || i == 3_000 || (7_000..7_002).contains(&i) || (12_000..12_300).contains(&i)
        };
        let (mut pushed, mut skipped, mut left_out) =
            (Welch::default(), Welch::default(), Welch::default());
        for i in 0..30_000u64 {
            let x = ((i * 37) % 101) as f64;
            let t = i * 2_000;
            pushed.push(t, x, !out(i));
            if out(i) {
                skipped.skip(t);
            } else {
                skipped.push(t, x, true);
                left_out.push(t, x, true);
            }
        }
        let (a, b) = (pushed.finish().unwrap(), skipped.finish().unwrap());
        assert!(a.segments > 50, "{}", a.segments);
        assert_eq!(a, b);
        assert_ne!(a, left_out.finish().unwrap());
    }

    /// Before the rate is known (the first 64 intervals), a sample out of flight ends the
    /// run too: the samples after it make the same estimate as a signal that starts there.
    #[test]
    fn a_run_ends_out_of_flight_before_the_rate_is_known() {
        let (mut cut, mut fresh) = (Welch::default(), Welch::default());
        for i in 0..20_000u64 {
            let x = ((i * 37) % 101) as f64;
            let t = i * 2_000;
            cut.push(t, x, i != 30);
            if i > 30 {
                fresh.push(t, x, true);
            }
        }
        assert_eq!(cut.finish().unwrap(), fresh.finish().unwrap());
    }

    #[test]
    fn a_sine_shows_at_its_frequency_with_its_power() {
        // 1 kHz sampling, a 50 Hz sine of amplitude 2 (power 2) and a little noise.
        let mut w = Welch::default();
        let mut noise = 0x9e37_79b9u32;
        for i in 0..20_000u64 {
            noise ^= noise << 13;
            noise ^= noise >> 17;
            noise ^= noise << 5;
            let t = i as f64 / 1000.0;
            let x = 2.0 * (2.0 * std::f64::consts::PI * 50.0 * t).sin()
                + (f64::from(noise) / f64::from(u32::MAX) - 0.5) * 0.01;
            w.push(i * 1000, x, true);
        }
        let s = w.finish().unwrap();
        assert_eq!(s.sample_rate_hz, 1000.0);
        assert_eq!(s.freq_hz.len(), 257, "512-point segments: 2 Hz resolution");
        let peak = (0..s.density.len())
            .max_by(|&a, &b| s.density[a].total_cmp(&s.density[b]))
            .unwrap();
        assert!((s.freq_hz[peak] - 50.0).abs() < 2.0, "{}", s.freq_hz[peak]);
        // The integral of the density is the signal's power (A²/2 = 2).
        let df = s.freq_hz[1];
        let power: f64 = s.density.iter().sum::<f64>() * df;
        assert!((power - 2.0).abs() < 0.05, "{power}");
        // A gap ends a run; samples out of flight are left out.
        let mut w = Welch::default();
        for i in 0..1000u64 {
            w.push(i * 1000, 1.0, i % 300 < 290);
        }
        assert!(w.finish().is_none(), "no run is a whole segment long");
    }
}
