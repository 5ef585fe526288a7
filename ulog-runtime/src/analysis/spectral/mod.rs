//! Spectral analyses of streamed signals: Welch's power spectral density ([`Welch`]) and
//! the rate controller's step response by Wiener deconvolution ([`StepResponse`]), over a
//! small FFT of our own ([`fft`]).

pub(crate) mod fft;
mod psd;
mod step;

pub(crate) use psd::Welch;
pub(crate) use step::StepResponse;

/// The median of the first intervals between samples, µs: a signal's sampling interval.
#[derive(Debug, Clone, Default)]
pub(crate) struct Interval {
    last: Option<u64>,
    seen: Vec<u64>,
    median: Option<u64>,
}

/// Intervals looked at before the median is taken.
const INTERVALS: usize = 64;

impl Interval {
    /// Sees a sample's time; the median interval once known.
    #[inline]
    pub(crate) fn see(&mut self, t: u64) -> Option<u64> {
        if self.median.is_none() {
            self.learn(t);
        }
        self.last = Some(t);
        self.median
    }

    /// Takes one more interval, until there are enough for the median.
    #[cold]
    fn learn(&mut self, t: u64) {
        if let Some(last) = self.last
            && t > last
        {
            self.seen.push(t - last);
        }
        if self.seen.len() >= INTERVALS {
            self.seen.sort_unstable();
            self.median = Some(self.seen[self.seen.len() / 2].max(1));
            self.seen = Vec::new();
        }
    }
}

/// Whether a sample at `t` µs breaks a run of samples whose last was at `last`, `dt_us`
/// apart: it is not after the last, or more than three intervals after it (the product
/// saturates: crafted timestamps and intervals near `u64::MAX` do not overflow).
#[inline]
pub(crate) fn breaks_run(last: u64, t: u64, dt_us: u64) -> bool {
    t <= last || t - last > dt_us.saturating_mul(3)
}

/// The symmetric Hann window of `n` points (`0.5 - 0.5 cos(2πk/(n-1))`), as numpy's
/// `hanning`.
pub(crate) fn hann_symmetric(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / (n - 1) as f64).cos())
        .collect()
}

/// The periodic Hann window of `n` points (`0.5 - 0.5 cos(2πk/n)`), as scipy's `welch`.
pub(crate) fn hann_periodic(n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * k as f64 / n as f64).cos())
        .collect()
}
