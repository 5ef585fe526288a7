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

#[cfg(test)]
mod tests {
    use super::*;

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
