//! The step response of a rate controller, from its setpoint and the measured rate, by
//! Wiener deconvolution, as Flight Review's PID analysis (after Plasmatree's PID-Analyzer)
//! computes it, as the samples stream.

use super::fft::{Complex, Fft, RealFft};
use super::{Interval, breaks_run, hann_symmetric};

/// The analysis rate: the gyro's, at most this (a 0.5 s response needs no more).
const MAX_RATE_HZ: f64 = 500.0;
/// Window length and response length, s.
const FRAME_S: f64 = 1.0;
const RESPONSE_S: f64 = 0.5;
/// Windows start every `frame / SUPERPOSITION` samples.
const SUPERPOSITION: usize = 16;
/// The deconvolution's cut-off, Hz.
const CUTOFF_HZ: f64 = 25.0;
/// A window's setpoint must reach this (deg/s) to count; above `HIGH` it counts apart.
const LOW: f64 = 20.0;
const HIGH: f64 = 500.0;
/// Fewest windows for a response.
const MIN_WINDOWS: usize = 10;
/// The averaging histogram's amplitudes.
const AMPLITUDES: usize = 1000;
const AMPLITUDE_MIN: f64 = -1.5;
const AMPLITUDE_MAX: f64 = 3.5;

/// One axis: setpoint and measured rate (deg/s) resampled to one grid, windowed,
/// deconvolved, the windows' steps accumulated.
///
/// What is computed, as Flight Review does: 1 s windows every 1/16 s, a symmetric Hann
/// taper, zero-padded to 1024 points; per window the impulse response
/// `h = Re IFFT(Y·conj(U) / (|U|² + 1/SNR))`, `SNR = 10` below 25 Hz rolling off through a
/// Gaussian-smoothed mask; its first 0.5 s summed into the step; windows whose tapered
/// setpoint peaks above 20 deg/s count (at least 10 are needed), those above 500 deg/s
/// apart; the response the mode-seeking average of their steps (a histogram of 1000
/// amplitudes over [-1.5, 3.5], smoothed by σ = 7 bins, each time normalized, weights H²).
/// Differences, for streaming: the grid is the gyro's median rate (at most 500 Hz), with
/// the setpoint held from its last sample, and windows lie within in-flight runs.
#[derive(Debug, Clone, Default)]
pub(crate) struct StepResponse {
    interval: Interval,
    state: Option<State>,
    setpoint: Option<f64>,
    /// The last gyro sample, for interpolation.
    last: Option<(u64, f64)>,
}

#[derive(Debug, Clone)]
struct State {
    dt_us: u64,
    next_t: u64,
    flen: usize,
    rlen: usize,
    shift: usize,
    since: usize,
    /// The last `flen` samples of the setpoint and the rate: rings of `2 × flen`, each
    /// sample written at `next` and `next + flen`, so that the last `flen` samples, oldest
    /// first, are always the slice `[next, next + flen)` (`next` the oldest once full).
    u: Vec<f64>,
    y: Vec<f64>,
    next: usize,
    filled: usize,
    /// How many setpoints in the ring are above 20 deg/s: a window with none is skipped
    /// before its taper is computed (the taper only shrinks values).
    above_low: usize,
    window: Vec<f64>,
    /// Both signals of a window in one transform (the setpoint real, the rate imaginary).
    fft: Fft,
    /// The impulse response back from its half spectrum.
    real: RealFft,
    inv_snr: Vec<f64>,
    low: Histogram,
    high: Histogram,
    both: Vec<Complex>,
    half: Vec<Complex>,
    impulse: Vec<f64>,
}

#[derive(Debug, Clone)]
struct Histogram {
    /// `AMPLITUDES × rlen`, amplitude-major: a step's next point is most often in the
    /// same amplitude bin or one near it, so its count is near the last one's in memory.
    counts: Vec<f32>,
    windows: usize,
}

/// An axis's response: time (s) and the averaged step, for windows up to 500 deg/s and,
/// if enough, above.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Response {
    pub(crate) sample_rate_hz: f64,
    pub(crate) time_s: Vec<f64>,
    pub(crate) low: Option<(usize, Vec<f64>)>,
    pub(crate) high: Option<(usize, Vec<f64>)>,
}

impl StepResponse {
    /// A rate setpoint sample (deg/s).
    pub(crate) fn setpoint(&mut self, value: f64) {
        if value.is_finite() {
            self.setpoint = Some(value);
        }
    }

    /// A measured rate sample (deg/s) at `t` µs; `keep` false, or a value that is not
    /// finite, ends the current run (the next starts at its first sample, as after
    /// [`StepResponse::skip`]).
    pub(crate) fn gyro(&mut self, t: u64, value: f64, keep: bool) {
        // What the next sample interpolates from: nothing after a sample out of flight or
        // not finite (its run starts at its own first sample).
        let sample = (keep && value.is_finite()).then_some((t, value));
        let Some(dt) = self.interval.see(t) else {
            self.last = sample;
            return;
        };
        let state = self.state.get_or_insert_with(|| State::new(dt, t));
        if state.flen < 2 {
            // A gyro logged every second or slower: no frame holds two samples, so no step.
            self.last = sample;
            return;
        }
        let (Some((t0, v0)), Some(sp)) = (self.last, self.setpoint) else {
            if self.last.is_none() {
                // A run's first sample (after a skipped one, say): the grid starts here.
                state.reset(t);
            }
            self.last = sample;
            return;
        };
        self.last = sample;
        if sample.is_none() || breaks_run(t0, t, dt.max(state.dt_us)) {
            state.reset(t);
            return;
        }
        // Grid points between the last sample and this one, interpolated (the last grid
        // point of time ends it, at the end of `u64`).
        while state.next_t <= t {
            if state.next_t >= t0 {
                let f = (state.next_t - t0) as f64 / (t - t0) as f64;
                state.push(sp, v0 + f * (value - v0));
            }
            match state.next_t.checked_add(state.dt_us) {
                Some(next) => state.next_t = next,
                None => break,
            }
        }
    }

    /// A measured rate sample at `t` µs out of flight: it ends the current run, and the
    /// next run's grid starts at its first sample in flight (the value is not needed: it is
    /// read only in flight).
    #[inline]
    pub(crate) fn skip(&mut self, t: u64) {
        // The interval is learnt from every sample; the next sample in flight finds no last
        // one and starts the grid (`gyro`).
        self.interval.see(t);
        self.last = None;
    }

    /// Whether enough windows counted: [`StepResponse::finish`] gives a response.
    pub(crate) fn has_response(&self) -> bool {
        self.state
            .as_ref()
            .is_some_and(|s| s.low.windows >= MIN_WINDOWS || s.high.windows >= MIN_WINDOWS)
    }

    /// The response, if enough windows counted.
    pub(crate) fn finish(self) -> Option<Response> {
        let s = self.state?;
        let dt = s.dt_us as f64 / 1e6;
        let low = s.low.average();
        let high = s.high.average();
        (low.is_some() || high.is_some()).then(|| Response {
            sample_rate_hz: 1.0 / dt,
            time_s: (0..s.rlen).map(|k| k as f64 * dt).collect(),
            low,
            high,
        })
    }
}

impl State {
    fn new(gyro_dt_us: u64, t: u64) -> State {
        let min_dt = (1e6 / MAX_RATE_HZ) as u64;
        let dt_us = gyro_dt_us.max(min_dt);
        let fs = 1e6 / dt_us as f64;
        let flen = (FRAME_S * fs) as usize;
        let rlen = (RESPONSE_S * fs) as usize;
        // Zero-padded to the next multiple of 1024 (at most 500 Hz: 1024).
        let len = 1024;
        let dt = 1.0 / fs;
        State {
            dt_us,
            next_t: t,
            flen,
            rlen,
            shift: (flen / SUPERPOSITION).max(1),
            since: 0,
            u: vec![0.0; 2 * flen],
            y: vec![0.0; 2 * flen],
            next: 0,
            filled: 0,
            above_low: 0,
            window: hann_symmetric(flen),
            fft: Fft::new(len),
            real: RealFft::new(len),
            inv_snr: inverse_snr(len, dt),
            low: Histogram::new(rlen),
            high: Histogram::new(rlen),
            both: vec![Complex::default(); len],
            half: vec![Complex::default(); len / 2 + 1],
            impulse: vec![0.0; len],
        }
    }

    fn reset(&mut self, t: u64) {
        self.next = 0;
        self.filled = 0;
        self.since = 0;
        self.next_t = t;
        self.above_low = 0;
    }

    #[inline]
    fn push(&mut self, u: f64, y: f64) {
        if self.filled == self.flen {
            // The oldest sample, which this one replaces.
            self.above_low -= usize::from(self.u[self.next].abs() > LOW);
        }
        self.above_low += usize::from(u.abs() > LOW);
        let (a, b) = (self.next, self.next + self.flen);
        (self.u[a], self.u[b]) = (u, u);
        (self.y[a], self.y[b]) = (y, y);
        self.next = if self.next + 1 == self.flen {
            0
        } else {
            self.next + 1
        };
        self.filled = (self.filled + 1).min(self.flen);
        self.since += 1;
        if self.filled == self.flen && self.since >= self.shift {
            self.since = 0;
            self.window_step();
        }
    }

    /// The last `flen` samples of a ring, oldest first.
    fn oldest_first<'r>(&self, ring: &'r [f64]) -> &'r [f64] {
        &ring[self.next..self.next + self.flen]
    }

    fn window_step(&mut self) {
        if self.above_low == 0 {
            return;
        }
        let peak = self
            .oldest_first(&self.u)
            .iter()
            .zip(&self.window)
            .map(|(u, w)| (u * w).abs())
            .fold(0.0, f64::max);
        if peak <= LOW {
            return;
        }
        let len = self.fft.len();
        let samples = self
            .oldest_first(&self.u)
            .iter()
            .zip(self.oldest_first(&self.y))
            .zip(&self.window);
        for (z, ((u, y), w)) in self.both.iter_mut().zip(samples) {
            *z = Complex::new(u * w, y * w);
        }
        for z in &mut self.both[self.flen..len] {
            *z = Complex::default();
        }
        self.fft.forward(&mut self.both);
        // U[k] = (Z[k] + conj Z[-k]) / 2, Y[k] = (Z[k] - conj Z[-k]) / 2i; the impulse
        // response's spectrum H = Y conj(U) / (|U|² + 1/SNR) is Hermitian (real signals,
        // a symmetric mask): its first half gives it.
        for k in 0..=len / 2 {
            let a = self.both[k];
            let b = self.both[(len - k) % len].conj();
            let u = Complex::new((a.re + b.re) * 0.5, (a.im + b.im) * 0.5);
            let y = Complex::new((a.im - b.im) * 0.5, -(a.re - b.re) * 0.5);
            self.half[k] = y
                .mul(u.conj())
                .scale(1.0 / (u.norm_sqr() + self.inv_snr[k]));
        }
        self.real.inverse(&mut self.half, &mut self.impulse);
        let mut step = 0.0;
        let hist = if peak <= HIGH {
            &mut self.low
        } else {
            &mut self.high
        };
        for (n, h) in self.impulse[..self.rlen].iter().enumerate() {
            step += h;
            hist.add(n, step);
        }
        hist.windows += 1;
    }
}

impl Histogram {
    fn new(rlen: usize) -> Histogram {
        Histogram {
            counts: vec![0.0; rlen * AMPLITUDES],
            windows: 0,
        }
    }

    fn add(&mut self, n: usize, value: f64) {
        let x = (value - AMPLITUDE_MIN) / (AMPLITUDE_MAX - AMPLITUDE_MIN) * AMPLITUDES as f64;
        if (0.0..=AMPLITUDES as f64).contains(&x) {
            let bin = (x as usize).min(AMPLITUDES - 1);
            let at = bin * self.rlen() + n;
            self.counts[at] += 1.0;
        }
    }

    /// Points of the response (the counts' time axis).
    fn rlen(&self) -> usize {
        self.counts.len() / AMPLITUDES
    }

    /// The mode-seeking average over time, if enough windows counted.
    fn average(&self) -> Option<(usize, Vec<f64>)> {
        if self.windows < MIN_WINDOWS {
            return None;
        }
        let kernel = gaussian_kernel(7.0);
        let ys: Vec<f64> = (0..AMPLITUDES)
            .map(|j| {
                AMPLITUDE_MIN + (AMPLITUDE_MAX - AMPLITUDE_MIN) * j as f64 / (AMPLITUDES - 1) as f64
            })
            .collect();
        let rlen = self.rlen();
        let avr = (0..rlen)
            .map(|n| {
                let column: Vec<f64> = (0..AMPLITUDES)
                    .map(|bin| f64::from(self.counts[bin * rlen + n]))
                    .collect();
                let smooth = convolve_constant(&column, &kernel);
                let max = smooth.iter().copied().fold(0.0, f64::max);
                if max <= 0.0 {
                    return 0.0;
                }
                let (mut num, mut den) = (0.0, 0.0);
                for (h, y) in smooth.iter().zip(&ys) {
                    let w = (h / max).powi(2);
                    num += y * w;
                    den += w;
                }
                num / den
            })
            .collect();
        Some((self.windows, avr))
    }
}

/// `1 / SNR` per FFT bin: `SNR = 10` below the cut-off, rolling off through a mask
/// smoothed by a Gaussian of a sixth of the pass band's bins (scipy's
/// `gaussian_filter1d`, mode `reflect`), as Flight Review builds it.
fn inverse_snr(len: usize, dt: f64) -> Vec<f64> {
    let freq: Vec<f64> = (0..len)
        .map(|k| {
            let k = if k < len.div_ceil(2) {
                k as f64
            } else {
                k as f64 - len as f64
            };
            (k / (len as f64 * dt)).abs()
        })
        .collect();
    let mask: Vec<f64> = to_mask(
        &freq
            .iter()
            .map(|f| f.clamp(CUTOFF_HZ - 1e-9, CUTOFF_HZ))
            .collect::<Vec<_>>(),
    );
    let pass: f64 = mask.iter().map(|m| 1.0 - m).sum();
    let smooth = to_mask(&convolve_reflect(&mask, &gaussian_kernel(pass / 6.0)));
    smooth
        .iter()
        .map(|m| 1.0 / (10.0 * (1.0 - m + 1e-9)))
        .collect()
}

/// `(x - min) / max(x - min)`, left as `x - min` when that maximum is below 1e-10.
fn to_mask(x: &[f64]) -> Vec<f64> {
    let min = x.iter().copied().fold(f64::INFINITY, f64::min);
    let shifted: Vec<f64> = x.iter().map(|v| v - min).collect();
    let max = shifted.iter().copied().fold(0.0, f64::max);
    if max > 1e-10 {
        shifted.iter().map(|v| v / max).collect()
    } else {
        shifted
    }
}

/// A normalized Gaussian kernel of `sigma`, radius `⌊4σ + 0.5⌋` (scipy's default).
fn gaussian_kernel(sigma: f64) -> Vec<f64> {
    let radius = (4.0 * sigma + 0.5) as i64;
    let k: Vec<f64> = (-radius..=radius)
        .map(|i| (-0.5 * (i as f64 / sigma).powi(2)).exp())
        .collect();
    let sum: f64 = k.iter().sum();
    k.iter().map(|v| v / sum).collect()
}

/// Convolution with the edges mirrored (`d c b a | a b c d | d c b a`).
fn convolve_reflect(x: &[f64], kernel: &[f64]) -> Vec<f64> {
    let n = x.len() as i64;
    let r = (kernel.len() / 2) as i64;
    // The signal with `r` mirrored values each side (mirrored again as often as the kernel
    // is wider than the signal).
    let padded: Vec<f64> = (-r..n + r)
        .map(|i| {
            let period = 2 * n;
            let m = i.rem_euclid(period);
            x[(if m < n { m } else { period - 1 - m }) as usize]
        })
        .collect();
    padded
        .windows(kernel.len())
        .map(|w| w.iter().zip(kernel).map(|(v, k)| v * k).sum())
        .collect()
}

/// Convolution with zeros beyond the edges, of a signal that is mostly zeros (a
/// histogram's column): each value spread over its neighbours.
fn convolve_constant(x: &[f64], kernel: &[f64]) -> Vec<f64> {
    let r = kernel.len() / 2;
    let mut out = vec![0.0; x.len()];
    for (j, &v) in x.iter().enumerate() {
        if v == 0.0 {
            continue;
        }
        // out[i] = Σ_k kernel[k] x[i + k - r]: x[j] reaches i = j + r - k.
        for (k, w) in kernel.iter().enumerate() {
            if let Some(o) = (j + r).checked_sub(k).and_then(|i| out.get_mut(i)) {
                *o += w * v;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A first-order loop with a time constant and a delay, under square-wave steps.
    fn loop_response(tau_s: f64, delay_s: f64) -> Response {
        let mut s = StepResponse::default();
        let fs = 250.0;
        let mut y = 0.0;
        let mut history = std::collections::VecDeque::new();
        let delay = (delay_s * fs) as usize;
        for i in 0..(60.0 * fs) as u64 {
            let t = i as f64 / fs;
            // Steps of ±300 deg/s every 0.2 s.
            let sp = if ((t / 0.2) as u64).is_multiple_of(2) {
                300.0
            } else {
                -300.0
            };
            history.push_back(sp);
            let delayed = if history.len() > delay {
                history.pop_front().unwrap()
            } else {
                0.0
            };
            y += (delayed - y) / (tau_s * fs);
            s.setpoint(sp);
            s.gyro((t * 1e6) as u64, y, true);
        }
        s.finish().unwrap()
    }

    /// After samples out of flight, a run's grid starts at its first sample in flight: 200
    /// Hz, 1 s windows every 12 samples, so `200 + 10 × 12 - 1` samples in flight make 10
    /// windows (11 had the last sample before takeoff started the run). The same after a
    /// flight and a stretch of two samples on the ground (less than the three intervals
    /// that break a run by time): the run before counts nothing.
    #[test]
    fn a_run_after_skipped_samples_starts_at_its_first_sample_in_flight() {
        let windows = |before: u64, in_flight: u64| {
            let mut s = StepResponse::default();
            s.setpoint(100.0);
            let dt = 5_000;
            let mut t = 0;
            let mut sample = |s: &mut StepResponse, keep: bool| {
                t += dt;
                if keep {
                    s.gyro(t, 90.0 + (t / dt % 7) as f64, true);
                } else {
                    s.skip(t);
                }
            };
            for _ in 0..300 {
                sample(&mut s, false);
            }
            for _ in 0..before {
                sample(&mut s, true);
            }
            for _ in 0..2 {
                sample(&mut s, false);
            }
            for _ in 0..in_flight {
                sample(&mut s, true);
            }
            s.finish().and_then(|r| r.low).map(|(n, _)| n)
        };
        assert_eq!(windows(0, 200 + 10 * 12 - 1), Some(10));
        assert_eq!(windows(0, 200 + 10 * 12), Some(11));
        assert_eq!(windows(0, 200 + 9 * 12 - 1), None, "9 windows are too few");
        // 150 samples before: no window of their own, none with the ones after.
        assert_eq!(windows(150, 200 + 10 * 12 - 1), Some(10));
    }

    /// A rate that is not finite in flight ends the run as a sample out of flight does: the
    /// same response as skipping it (before, the next grid point interpolated from it, and
    /// the windows holding that NaN counted with no step).
    #[test]
    fn a_rate_that_is_not_finite_ends_the_run() {
        let response = |nan: bool| {
            let mut s = StepResponse::default();
            for i in 0..5_000u64 {
                let sp = if (i / 50) % 2 == 0 { 100.0 } else { -100.0 };
                s.setpoint(sp);
                let t = i * 4_000;
                if i == 2_000 && nan {
                    s.gyro(t, f64::NAN, true);
                } else if i == 2_000 {
                    s.skip(t);
                } else {
                    s.gyro(t, sp * 0.9, true);
                }
            }
            s.finish().unwrap()
        };
        let (with_nan, skipped) = (response(true), response(false));
        let (windows, step) = with_nan.low.clone().unwrap();
        assert!(step.iter().all(|v| v.is_finite()));
        assert_eq!(with_nan, skipped);
        // Two runs: 2000 and 2999 samples at 250 Hz, windows every 15 samples.
        assert_eq!(
            windows,
            (1 + (2_000 - 64 - 1 - 250) / 15) + (1 + (2_999 - 250) / 15)
        );
    }

    /// A flight, samples out of flight, and a flight at 7e18 µs: the second run's grid
    /// starts at its first sample (not at the last skipped one, 7e18 µs of grid points
    /// before).
    #[test]
    fn a_run_after_a_time_jump_starts_at_its_first_sample() {
        let windows = windows_within_a_minute(|s| {
            for i in 0..400 {
                s.gyro(i * 5_000, 90.0, true);
            }
            for i in 400..410 {
                s.skip(i * 5_000);
            }
            for i in 0..1_000 {
                s.gyro(7_000_000_000_000_000_000 + i * 5_000, 90.0, true);
            }
        });
        // The first flight's windows and the second's.
        assert_eq!(
            windows,
            Some(1 + (400 - 64 - 200) / 12 + 1 + (1_000 - 200) / 12)
        );
    }

    #[test]
    fn a_first_order_loop_steps_as_its_model() {
        let r = loop_response(0.03, 0.01);
        assert_eq!(r.sample_rate_hz, 250.0);
        assert_eq!(r.time_s.len(), 125, "0.5 s");
        let (windows, step) = r.low.unwrap();
        assert!(windows > 100, "{windows}");
        let at = |s: f64| step[(s * 250.0) as usize];
        // The model: 0 until the delay, 1 - e^{-(t - delay)/tau} after.
        let model = |s: f64| {
            if s < 0.01 {
                0.0
            } else {
                1.0 - (-(s - 0.01) / 0.03f64).exp()
            }
        };
        for s in [0.1, 0.2, 0.4] {
            assert!(
                (at(s) - model(s)).abs() < 0.1,
                "{s}: {} vs {}",
                at(s),
                model(s)
            );
        }
        assert!(at(0.004) < 0.3, "before the loop answers: {}", at(0.004));
        assert!(r.high.is_none(), "no window above 500 deg/s");
        // A slower loop rises later.
        let slow = loop_response(0.1, 0.01).low.unwrap().1;
        assert!(slow[(0.05 * 250.0) as usize] < at(0.05) - 0.2);
    }

    /// Samples up to the last microsecond `u64` holds: the grid stops there (its next point
    /// would overflow; it wrapped around to 0 and looped again).
    #[test]
    fn samples_at_the_end_of_time_end_the_grid() {
        let windows = windows_within_a_minute(|s| {
            let n = 2_000u64;
            for i in 0..=n {
                s.gyro(u64::MAX - (n - i) * 4_000, 90.0 + (i % 5) as f64, true);
            }
        });
        // 2001 samples, the first 65 to learn the rate: windows of 250 every 15.
        assert_eq!(windows, Some(1 + (2_001 - 65 - 1 - 250) / 15));
    }

    /// The windows of the low response of a `StepResponse` (setpoint 100 deg/s) fed by
    /// `feed` on a thread of its own: a feed that loops for ever fails the test after a
    /// minute instead of hanging it.
    fn windows_within_a_minute(
        feed: impl FnOnce(&mut StepResponse) + Send + 'static,
    ) -> Option<usize> {
        let (done, finished) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            let mut s = StepResponse::default();
            s.setpoint(100.0);
            feed(&mut s);
            done.send(s.finish().and_then(|r| r.low).map(|(n, _)| n))
                .unwrap();
        });
        finished
            .recv_timeout(std::time::Duration::from_secs(60))
            .expect("fed within a minute")
    }

    #[test]
    fn a_gyro_logged_every_second_or_slower_gives_no_response_and_no_panic() {
        let steady = |dt_us: u64| (0..400u64).map(|i| i * dt_us).collect::<Vec<_>>();
        // Timestamps jumping between 0 and 7e18 µs: intervals (and their median) of 7e18.
        let jumping = (0..400u64)
            .map(|i| {
                if i % 2 == 1 {
                    7_000_000_000_000_000_000 + i
                } else {
                    i
                }
            })
            .collect();
        let clocks: [(&str, Vec<u64>); 3] = [
            ("1.0002 s", steady(1_000_200)),
            ("2 s", steady(2_000_000)),
            ("7e18 µs", jumping),
        ];
        for (name, times) in clocks {
            let mut s = StepResponse::default();
            for (i, t) in times.into_iter().enumerate() {
                s.setpoint(if i % 2 == 0 { 300.0 } else { -300.0 });
                s.gyro(t, (i % 7) as f64 * 50.0, true);
            }
            assert!(s.finish().is_none(), "{name}");
        }
    }

    #[test]
    fn too_little_input_gives_no_response() {
        let mut s = StepResponse::default();
        for i in 0..10_000u64 {
            s.setpoint(5.0);
            s.gyro(i * 4000, 5.0, true);
        }
        assert!(s.finish().is_none(), "setpoint below 20 deg/s");
    }

    #[test]
    fn the_snr_mask_passes_below_the_cutoff() {
        let inv = inverse_snr(1024, 1.0 / 250.0);
        assert!(
            (inv[1] - 0.1).abs() < 1e-4,
            "SNR 10 in the pass band: {}",
            inv[1]
        );
        // The mask's edge is smoothed over a sixth of the pass band: far above the
        // cutoff, the noise term dominates.
        let bin_100_hz = (100.0 * 1024.0 / 250.0) as usize;
        assert!(
            inv[bin_100_hz] > 1e3,
            "suppressed above: {}",
            inv[bin_100_hz]
        );
        let bin_40_hz = (40.0 * 1024.0 / 250.0) as usize;
        assert!(
            inv[bin_40_hz] > 10.0 * inv[1],
            "damped at 40 Hz: {}",
            inv[bin_40_hz]
        );
        // Positive and negative frequencies alike (to the reflection at the array's ends).
        assert!((inv[5] - inv[1024 - 5]).abs() < 1e-3 * inv[5], "symmetric");
    }
}
