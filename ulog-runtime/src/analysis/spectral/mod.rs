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

/// Properties of both analyses over any sequence of samples: a sample skipped out of flight
/// is one fed out of flight (whatever its value), a rate that is not finite in flight is one
/// skipped, and no sequence (times jumping anywhere in `u64`, values not finite) panics or
/// makes a call loop for long. The sequences are runs of samples at 250 Hz, most in flight
/// and long enough for windows and segments, so that most cases compare estimates, not
/// their absence (counted: a property that compared nothing would fail).
#[cfg(test)]
mod properties {
    use super::{StepResponse, Welch};
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestRunner};
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A stretch of samples: in flight, out of flight, not finite (in flight), or a jump
    /// of the clock.
    #[derive(Debug, Clone, Copy)]
    enum Stretch {
        Flight(usize),
        Ground(usize),
        NotFinite(usize),
        Jump(u64),
    }

    /// Samples: (time, value, in flight).
    fn samples() -> impl Strategy<Value = Vec<(u64, f64, bool)>> {
        let stretch = prop_oneof![
            5 => (100usize..700).prop_map(Stretch::Flight),
            2 => (1usize..100).prop_map(Stretch::Flight),
            2 => (1usize..40).prop_map(Stretch::Ground),
            1 => (1usize..3).prop_map(Stretch::NotFinite),
            1 => prop_oneof![
                Just(0u64),
                8_000u64..20_000,
                Just(7_000_000_000_000_000_000),
                Just(u64::MAX),
            ]
            .prop_map(Stretch::Jump),
        ];
        proptest::collection::vec(stretch, 1..12).prop_map(|stretches| {
            let mut t = 0u64;
            let mut out = Vec::new();
            let mut wave = 0u64;
            for s in stretches {
                let (n, keep, finite) = match s {
                    Stretch::Flight(n) => (n, true, true),
                    Stretch::Ground(n) => (n, false, true),
                    Stretch::NotFinite(n) => (n, true, false),
                    Stretch::Jump(dt) => {
                        t = t.saturating_add(dt);
                        continue;
                    }
                };
                for _ in 0..n {
                    t = t.saturating_add(4_000);
                    wave += 1;
                    let x = if finite {
                        ((wave * 37) % 200) as f64 - 100.0
                    } else {
                        f64::NAN
                    };
                    out.push((t, x, keep));
                }
            }
            out
        })
    }

    /// Runs `property` on 96 sequences; returns how many gave an estimate.
    fn check(property: impl Fn(&[(u64, f64, bool)]) -> bool) -> usize {
        let estimates = AtomicUsize::new(0);
        let mut runner = TestRunner::new(Config {
            cases: 96,
            failure_persistence: None,
            ..Config::default()
        });
        runner
            .run(&samples(), |s| {
                if property(&s) {
                    estimates.fetch_add(1, Ordering::Relaxed);
                }
                Ok(())
            })
            .unwrap();
        estimates.into_inner()
    }

    #[test]
    fn welch_skip_is_push_out_of_flight() {
        let estimates = check(|s| {
            let (mut pushed, mut skipped) = (Welch::default(), Welch::default());
            for &(t, x, keep) in s {
                pushed.push(t, x, keep);
                if keep {
                    skipped.push(t, x, true);
                } else {
                    skipped.skip(t);
                }
            }
            let (a, b) = (pushed.finish(), skipped.finish());
            assert_eq!(a, b, "{s:?}");
            a.is_some()
        });
        assert!(estimates > 20, "{estimates} of 96 cases made an estimate");
    }

    #[test]
    fn step_skip_is_gyro_out_of_flight_or_not_finite() {
        let responses = check(|s| {
            let (mut fed, mut skipped) = (StepResponse::default(), StepResponse::default());
            for (i, &(t, x, keep)) in s.iter().enumerate() {
                // A square wave above the threshold: the windows count.
                let sp = if (i / 40) % 2 == 0 { 100.0 } else { -100.0 };
                fed.setpoint(sp);
                skipped.setpoint(sp);
                fed.gyro(t, x, keep);
                if keep && x.is_finite() {
                    skipped.gyro(t, x, true);
                } else {
                    skipped.skip(t);
                }
            }
            let (a, b) = (fed.finish(), skipped.finish());
            assert_eq!(a, b, "{s:?}");
            a.is_some()
        });
        assert!(responses > 20, "{responses} of 96 cases made a response");
    }
}
