//! A radix-2 fast Fourier transform over complex numbers (lengths that are powers of two):
//! all the spectral analyses need, without a dependency.

/// A complex number.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Complex {
    pub(crate) re: f64,
    pub(crate) im: f64,
}

impl Complex {
    pub(crate) fn new(re: f64, im: f64) -> Complex {
        Complex { re, im }
    }

    pub(crate) fn norm_sqr(self) -> f64 {
        self.re * self.re + self.im * self.im
    }

    pub(crate) fn conj(self) -> Complex {
        Complex::new(self.re, -self.im)
    }

    pub(crate) fn mul(self, o: Complex) -> Complex {
        Complex::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }

    pub(crate) fn scale(self, k: f64) -> Complex {
        Complex::new(self.re * k, self.im * k)
    }
}

/// A plan for transforms of one length: the bit-reversal permutation and the twiddles.
#[derive(Debug, Clone)]
pub(crate) struct Fft {
    n: usize,
    reversed: Vec<usize>,
    twiddles: Vec<Complex>,
}

impl Fft {
    /// A plan for length `n`, a power of two (at least 2).
    pub(crate) fn new(n: usize) -> Fft {
        assert!(
            n.is_power_of_two() && n >= 2,
            "FFT lengths are powers of two"
        );
        let bits = n.trailing_zeros();
        let reversed = (0..n)
            .map(|i| i.reverse_bits() >> (usize::BITS - bits))
            .collect();
        let twiddles = (0..n / 2)
            .map(|k| {
                let a = -2.0 * std::f64::consts::PI * k as f64 / n as f64;
                Complex::new(a.cos(), a.sin())
            })
            .collect();
        Fft {
            n,
            reversed,
            twiddles,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// The forward transform in place: `X[k] = Σ x[n] e^{-2πikn/N}` (not normalized).
    pub(crate) fn forward(&self, x: &mut [Complex]) {
        self.transform(x, false);
    }

    /// The inverse transform in place, normalized by `1/N`.
    pub(crate) fn inverse(&self, x: &mut [Complex]) {
        self.transform(x, true);
        let k = 1.0 / self.n as f64;
        for v in x.iter_mut() {
            *v = v.scale(k);
        }
    }

    fn transform(&self, x: &mut [Complex], inverse: bool) {
        assert_eq!(x.len(), self.n, "the plan's length");
        for i in 0..self.n {
            let j = self.reversed[i];
            if i < j {
                x.swap(i, j);
            }
        }
        let mut len = 2;
        while len <= self.n {
            let step = self.n / len;
            for start in (0..self.n).step_by(len) {
                for k in 0..len / 2 {
                    let w = self.twiddles[k * step];
                    let w = if inverse { w.conj() } else { w };
                    let a = x[start + k];
                    let b = x[start + k + len / 2].mul(w);
                    x[start + k] = Complex::new(a.re + b.re, a.im + b.im);
                    x[start + k + len / 2] = Complex::new(a.re - b.re, a.im - b.im);
                }
            }
            len *= 2;
        }
    }
}

/// Transforms of real signals of one length `n` (a power of two, at least 4), through a
/// complex transform of half the length: the even samples as the real parts, the odd ones as
/// the imaginary parts, the two halves of the spectrum untangled after.
#[derive(Debug, Clone)]
pub(crate) struct RealFft {
    n: usize,
    half: Fft,
    /// `e^{-2πik/n}`, `k < n/2`.
    twiddles: Vec<Complex>,
}

impl RealFft {
    /// A plan for real signals of length `n`, a power of two (at least 4).
    pub(crate) fn new(n: usize) -> RealFft {
        assert!(
            n.is_power_of_two() && n >= 4,
            "real FFT lengths are powers of two"
        );
        let twiddles = (0..n / 2)
            .map(|k| {
                let a = -2.0 * std::f64::consts::PI * k as f64 / n as f64;
                Complex::new(a.cos(), a.sin())
            })
            .collect();
        RealFft {
            n,
            half: Fft::new(n / 2),
            twiddles,
        }
    }

    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// The first `n/2 + 1` bins of the forward transform of the real signal `x` (the rest
    /// are their conjugates) into `out`, which has room for `n/2 + 1`.
    pub(crate) fn forward(&self, x: &[f64], out: &mut [Complex]) {
        let h = self.n / 2;
        assert!(
            x.len() == self.n && out.len() == h + 1,
            "the plan's lengths"
        );
        for (z, pair) in out[..h].iter_mut().zip(x.chunks_exact(2)) {
            *z = Complex::new(pair[0], pair[1]);
        }
        self.half.forward(&mut out[..h]);
        // Z[k] = E[k] + i O[k], with E and O the transforms of the even and odd samples:
        // E[k] = (Z[k] + conj Z[h-k]) / 2, O[k] = (Z[k] - conj Z[h-k]) / 2i, and
        // X[k] = E[k] + w^k O[k], X[h-k] = conj(E[k] - w^k O[k]).
        let z0 = out[0];
        out[0] = Complex::new(z0.re + z0.im, 0.0);
        out[h] = Complex::new(z0.re - z0.im, 0.0);
        for k in 1..=h / 2 {
            let (a, b) = (out[k], out[h - k].conj());
            let even = Complex::new((a.re + b.re) * 0.5, (a.im + b.im) * 0.5);
            // (a - b) / 2i = (Im(a - b), -Re(a - b)) / 2.
            let odd = Complex::new((a.im - b.im) * 0.5, -(a.re - b.re) * 0.5);
            let t = self.twiddles[k].mul(odd);
            out[k] = Complex::new(even.re + t.re, even.im + t.im);
            out[h - k] = Complex::new(even.re - t.re, -(even.im - t.im));
        }
    }

    /// The real signal whose transform's first `n/2 + 1` bins are `spectrum` (Hermitian: the
    /// rest their conjugates), normalized by `1/n`, into `out` (length `n`); `spectrum` is
    /// used as room and left changed.
    pub(crate) fn inverse(&self, spectrum: &mut [Complex], out: &mut [f64]) {
        let h = self.n / 2;
        assert!(
            spectrum.len() == h + 1 && out.len() == self.n,
            "the plan's lengths"
        );
        // The forward untangling undone: E[k] = (X[k] + conj X[h-k]) / 2,
        // O[k] = w^-k (X[k] - conj X[h-k]) / 2, and Z[k] = E[k] + i O[k].
        let (x0, xh) = (spectrum[0], spectrum[h]);
        spectrum[0] = Complex::new((x0.re + xh.re) * 0.5, (x0.re - xh.re) * 0.5);
        for k in 1..=h / 2 {
            let (a, b) = (spectrum[k], spectrum[h - k].conj());
            let even = Complex::new((a.re + b.re) * 0.5, (a.im + b.im) * 0.5);
            let t = Complex::new((a.re - b.re) * 0.5, (a.im - b.im) * 0.5);
            let odd = self.twiddles[k].conj().mul(t);
            // Z[h-k] = E[h-k] + i O[h-k], with E[h-k] = conj E[k] and O[h-k] = conj O[k]
            // (the transforms of real sequences).
            spectrum[k] = Complex::new(even.re - odd.im, even.im + odd.re);
            spectrum[h - k] = Complex::new(even.re + odd.im, -even.im + odd.re);
        }
        self.half.inverse(&mut spectrum[..h]);
        for (pair, z) in out.chunks_exact_mut(2).zip(&spectrum[..h]) {
            pair[0] = z.re;
            pair[1] = z.im;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_real_transform_is_the_complex_one_of_a_real_signal() {
        for n in [4, 8, 16, 256, 1024] {
            let x: Vec<f64> = (0..n)
                .map(|i| (i as f64 * 0.37).sin() * 3.0 + (i as f64 * 1.9).cos() + 0.25)
                .collect();
            let mut full: Vec<Complex> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
            Fft::new(n).forward(&mut full);
            let plan = RealFft::new(n);
            let mut half = vec![Complex::default(); n / 2 + 1];
            plan.forward(&x, &mut half);
            for (k, (got, want)) in half.iter().zip(&full).enumerate() {
                assert!(
                    (got.re - want.re).abs() < 1e-9 && (got.im - want.im).abs() < 1e-9,
                    "n {n}, bin {k}: {got:?} vs {want:?}"
                );
            }
            let mut back = vec![0.0; n];
            plan.inverse(&mut half, &mut back);
            for (i, (a, b)) in back.iter().zip(&x).enumerate() {
                assert!((a - b).abs() < 1e-12, "n {n}, sample {i}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn the_transform_is_the_discrete_fourier_transform() {
        let n = 16;
        let x: Vec<Complex> = (0..n)
            .map(|i| Complex::new((i as f64 * 0.7).sin() + 0.3, (i as f64 * 0.2).cos()))
            .collect();
        let mut fast = x.clone();
        Fft::new(n).forward(&mut fast);
        for (k, got) in fast.iter().enumerate() {
            let mut want = Complex::default();
            for (i, v) in x.iter().enumerate() {
                let a = -2.0 * std::f64::consts::PI * (k * i) as f64 / n as f64;
                let w = v.mul(Complex::new(a.cos(), a.sin()));
                want = Complex::new(want.re + w.re, want.im + w.im);
            }
            assert!(
                (got.re - want.re).abs() < 1e-9 && (got.im - want.im).abs() < 1e-9,
                "{k}"
            );
        }
        Fft::new(n).inverse(&mut fast);
        for (a, b) in fast.iter().zip(&x) {
            assert!((a.re - b.re).abs() < 1e-12 && (a.im - b.im).abs() < 1e-12);
        }
    }
}
