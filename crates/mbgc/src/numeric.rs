//! Small numeric tools shared across the pipeline: seed mixing, a stable fingerprint hash,
//! quantiles and sample moments. One copy each, so every stage mixes seeds and reads quantiles
//! the same way.

pub use mbgc_sr::seed::splitmix64;

/// 64-bit FNV-1a: a stable fingerprint (run ids, training data), not a security hash.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fnv1a(pub u64);

impl Default for Fnv1a {
    fn default() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv1a {
    const PRIME: u64 = 0x0000_0100_0000_01b3;

    /// Mixes raw bytes into the hash; no length prefix, so use [`Self::str`] for lists of strings.
    pub fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(Self::PRIME);
        }
    }

    /// A string with a length prefix, so that no two lists of strings share a byte stream
    /// (`ab` + `c` against `a` + `bc`).
    pub fn str(&mut self, s: &str) {
        self.bytes(&(s.len() as u64).to_le_bytes());
        self.bytes(s.as_bytes());
    }

    /// Mixes an integer as its 8 little-endian bytes, so the hash is the same on every platform.
    pub fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
}

/// FNV-1a of a byte string.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a::default();
    h.bytes(bytes);
    h.0
}

/// Quantile of sorted values with linear interpolation between order statistics (type 7 of
/// Hyndman & Fan, the default of R and NumPy); `p` is clamped to [0, 1]; NaN for no values.
pub fn quantile_sorted(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let h = (sorted.len() - 1) as f64 * p.clamp(0.0, 1.0);
    let (i, f) = (h.floor() as usize, h.fract());
    match sorted.get(i + 1) {
        // The second form does not overflow for values of opposite sign near f64::MAX.
        Some(&next) if f > 0.0 => match next - sorted[i] {
            d if d.is_finite() => sorted[i] + f * d,
            _ => (1.0 - f) * sorted[i] + f * next,
        },
        _ => sorted[i],
    }
}

/// Quantile of unsorted values (see [`quantile_sorted`]).
pub fn quantile(values: &[f64], p: f64) -> f64 {
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    quantile_sorted(&v, p)
}

/// Pearson's correlation of two equally long samples; NaN when either is constant or shorter
/// than 2.
pub fn correlation(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len().min(y.len());
    if n < 2 {
        return f64::NAN;
    }
    let (mx, my) = (
        x[..n].iter().sum::<f64>() / n as f64,
        y[..n].iter().sum::<f64>() / n as f64,
    );
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x[..n].iter().zip(&y[..n]) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx == 0.0 || syy == 0.0 {
        return f64::NAN;
    }
    sxy / (sxx * syy).sqrt()
}

/// `v` rounded to `digits` significant decimal digits (the number a reader sees printed with
/// that many digits); zero and non-finite values unchanged.
pub fn round_significant(v: f64, digits: usize) -> f64 {
    if v == 0.0 || !v.is_finite() || digits == 0 {
        return v;
    }
    format!("{:.*e}", digits - 1, v).parse().unwrap_or(v)
}

/// `v` rounded to four significant digits for reading: the digits, and the power of ten they
/// are to be multiplied by when `v` is outside [1e-3, 1e4) (`None` inside, where plain decimals
/// read best). Trailing zeros are dropped: 1.4999999999999991 -> "1.5".
pub fn four_significant(v: f64) -> (String, Option<i32>) {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() {
        return (format!("{v}"), None);
    }
    if (1e-3..1e4).contains(&a) {
        let digits = (3 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.digits$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        (s, None)
    } else {
        let e = a.log10().floor() as i32;
        (format!("{:.3}", v / 10f64.powi(e)), Some(e))
    }
}

/// Mean and sample standard deviation (n - 1); the deviation is 0 for one value, both NaN for
/// none.
pub fn mean_sd(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let sd = if v.len() > 1 {
        (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    (m, sd)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn correlation_of_known_samples() {
        assert!((correlation(&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.5]) - 0.997_948_7).abs() < 1e-7);
        assert!((correlation(&[1.0, 2.0, 3.0], &[3.0, 2.0, 1.0]) + 1.0).abs() < 1e-12);
        assert!(correlation(&[1.0, 1.0], &[1.0, 2.0]).is_nan());
    }

    #[test]
    fn rounds_to_significant_digits() {
        assert_eq!(round_significant(0.07957747154594767, 4), 0.07958);
        assert_eq!(round_significant(-1234.5678, 4), -1235.0);
        assert_eq!(round_significant(6.0221e23, 2), 6.0e23);
        assert_eq!(round_significant(0.0, 4), 0.0);
        assert!(round_significant(f64::NAN, 4).is_nan());
    }

    #[test]
    fn fnv1a_matches_the_published_test_vectors() {
        // From the FNV reference (isthe.com/chongo/tech/comp/fnv): "" and "a" and "foobar".
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn splitmix64_matches_the_reference_generator() {
        // First outputs of Vigna's splitmix64.c seeded with 0: state advances by the golden
        // gamma and the output function is applied to the new state.
        assert_eq!(splitmix64(0), 0xe220_a839_7b1d_cdaf);
        assert_eq!(splitmix64(0x9e37_79b9_7f4a_7c15), 0x6e78_9e6a_a1b9_65f4);
    }

    #[test]
    fn quantiles_interpolate_like_numpy() {
        let v = [3.0, 1.0, 4.0, 1.0, 5.0];
        // numpy.quantile([3,1,4,1,5], [0, .25, .5, .9, 1]) = 1, 1, 3, 4.6, 5
        for (p, q) in [(0.0, 1.0), (0.25, 1.0), (0.5, 3.0), (0.9, 4.6), (1.0, 5.0)] {
            assert!(
                (quantile(&v, p) - q).abs() < 1e-12,
                "{p}: {}",
                quantile(&v, p)
            );
        }
        assert!(quantile(&[], 0.5).is_nan());
        assert_eq!(quantile_sorted(&[-f64::MAX, f64::MAX], 0.5), 0.0);
    }

    #[test]
    fn mean_sd_of_a_known_sample() {
        let (m, sd) = mean_sd(&[2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0]);
        assert_eq!(m, 5.0);
        assert!((sd - (32.0f64 / 7.0).sqrt()).abs() < 1e-15);
        assert_eq!(mean_sd(&[1.5]), (1.5, 0.0));
    }
}
