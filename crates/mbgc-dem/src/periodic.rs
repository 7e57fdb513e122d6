//! Periodic boundaries: the period box of a scene, wrapping of positions into it and the
//! minimum-image convention for pair separations.
//!
//! Along a periodic axis k, a particle at x and its images at x + m L_k (m integer) are the same
//! particle; a pair interacts through its nearest images. The convention is unambiguous only if
//! no pair can touch through two images at once, so [`crate::Simulation::new`] requires every
//! period to exceed twice the largest neighbour cutoff (2 r_max + skin).
//!
//! Positions are wrapped into the box at every neighbour-list rebuild, not every step: between
//! rebuilds a particle may stand up to skin / 2 outside it, and separations are corrected for
//! that ([`PeriodicBox::min_image`]).

use super::vec3::V3;

/// The period box: per axis, either periodic with period L_k from `lo[k]` (positions are taken
/// modulo L_k into `[lo[k], lo[k] + L_k)`), or not periodic (stored as an infinite period, so
/// that the minimum-image correction never fires along it without a test per axis).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicBox {
    lo: V3,
    period: V3,
    half: V3,
}

impl Default for PeriodicBox {
    fn default() -> Self {
        Self::NONE
    }
}

impl PeriodicBox {
    /// No periodic axis.
    pub const NONE: PeriodicBox = PeriodicBox {
        lo: [0.0; 3],
        period: [f64::INFINITY; 3],
        half: [f64::INFINITY; 3],
    };

    /// The box `domain` = (lo, hi), periodic along the axes flagged in `periodic` with period
    /// `hi[k] - lo[k]`. `None` if a periodic axis has a period that is not positive and finite.
    pub fn new(domain: (V3, V3), periodic: [bool; 3]) -> Option<PeriodicBox> {
        let mut b = Self::NONE;
        for k in (0..3).filter(|&k| periodic[k]) {
            let l = domain.1[k] - domain.0[k];
            if !(l.is_finite() && l > 0.0 && domain.0[k].is_finite()) {
                return None;
            }
            b.lo[k] = domain.0[k];
            b.period[k] = l;
            b.half[k] = 0.5 * l;
        }
        Some(b)
    }

    /// Whether axis k is periodic.
    #[inline]
    pub fn is_periodic(&self, k: usize) -> bool {
        self.period[k].is_finite()
    }

    /// Per axis, whether it is periodic.
    pub fn periodic(&self) -> [bool; 3] {
        std::array::from_fn(|k| self.is_periodic(k))
    }

    /// Whether some axis is periodic.
    pub fn any(&self) -> bool {
        (0..3).any(|k| self.is_periodic(k))
    }

    /// Lower corner of the period box, m (0 along non-periodic axes).
    pub fn lo(&self) -> V3 {
        self.lo
    }

    /// Periods, m (infinite along non-periodic axes).
    pub fn period(&self) -> V3 {
        self.period
    }

    /// `x` with its periodic coordinates taken into `[lo, lo + L)`; the others unchanged.
    #[inline]
    pub fn wrap(&self, mut x: V3) -> V3 {
        for ((c, &l), &lo) in x.iter_mut().zip(&self.period).zip(&self.lo) {
            if l.is_finite() {
                let mut u = (*c - lo).rem_euclid(l);
                // rem_euclid of a tiny negative number can round up to l itself.
                if u >= l {
                    u = 0.0;
                }
                *c = lo + u;
            }
        }
        x
    }

    /// The nearest image of a separation `d`: along each periodic axis, d_k shifted by one
    /// period into [-L/2, L/2]. One shift suffices for |d_k| < 3 L / 2, which holds for any two
    /// positions within skin / 2 of the box (the engine's between rebuilds); arbitrary positions
    /// must be [wrapped](PeriodicBox::wrap) first.
    #[inline(always)]
    pub fn min_image(&self, mut d: V3) -> V3 {
        for ((c, &h), &l) in d.iter_mut().zip(&self.half).zip(&self.period) {
            if *c > h {
                *c -= l;
            } else if *c < -h {
                *c += l;
            }
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_into_the_box_and_finds_the_nearest_image() {
        let b = PeriodicBox::new(([0.0, -1.0, 5.0], [2.0, 1.0, 9.0]), [true, true, false]).unwrap();
        assert_eq!(b.periodic(), [true, true, false]);
        let w = b.wrap([2.5, -3.5, 100.0]);
        assert!(
            (w[0] - 0.5).abs() < 1e-15 && (w[1] - 0.5).abs() < 1e-15,
            "{w:?}"
        );
        assert_eq!(w[2], 100.0, "a non-periodic coordinate is left alone");
        // The rounding edge: a coordinate a hair below lo must land in [lo, hi), not on hi.
        let w = b.wrap([-1e-300, 0.0, 0.0]);
        assert!(w[0] >= 0.0 && w[0] < 2.0, "{w:?}");
        let d = b.min_image([1.9, -1.5, 3.0]);
        assert!(
            (d[0] + 0.1).abs() < 1e-15 && (d[1] - 0.5).abs() < 1e-15,
            "{d:?}"
        );
        assert_eq!(d[2], 3.0);
        assert_eq!(
            PeriodicBox::NONE.min_image([1e30, -1e30, 0.0]),
            [1e30, -1e30, 0.0]
        );
        assert!(PeriodicBox::new(([0.0; 3], [0.0; 3]), [true, false, false]).is_none());
    }
}
