//! The velocity-Verlet kick and drift of a block of particles, with their forces reset to
//! gravity for the next force loop.
//!
//! Every component gets the same operations on the same values as the particle-by-particle
//! loop (`v += a f`, `x += dt v`, no fused multiply-add), so the results are the same to the
//! bit. With AVX2, four particles (twelve numbers, three vectors) go at a time, each particle's
//! factor spread over its three components: a loop over `[f64; 3]` stays scalar, and this pass
//! was a fifth of a settled box's step besides the force loop.

use crate::vec3::V3;

/// The arrays of one block of particles, all of the same length.
pub(crate) struct Block<'a> {
    pub x: &'a mut [V3],
    pub v: &'a mut [V3],
    pub w: &'a mut [V3],
    pub f: &'a mut [V3],
    pub t: &'a mut [V3],
    pub m: &'a [f64],
    pub inv_m: &'a [f64],
    pub inv_i: &'a [f64],
}

/// Particles per chunk: twelve numbers, three vectors of four.
const CHUNK: usize = 4;

/// Kicks the velocities by half a step of `dt` (twice from the same forces with `TWICE`: the
/// previous step's second half kick and this step's first), drifts the positions by a whole
/// step and resets the forces to `m g` and the torques to zero.
pub(crate) fn kick_drift<const TWICE: bool>(b: Block, dt: f64, g: V3) {
    let n = b.x.len();
    assert!(
        [
            b.v.len(),
            b.w.len(),
            b.f.len(),
            b.t.len(),
            b.m.len(),
            b.inv_m.len(),
            b.inv_i.len()
        ]
        .iter()
        .all(|&l| l == n),
        "kick_drift: the block's arrays differ in length"
    );
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2, checked just above.
        unsafe { kick_drift_avx2::<TWICE>(b, dt, g) };
        return;
    }
    kick_drift_plain::<TWICE>(b, dt, g)
}

/// The particle-by-particle loop: the reference, and the path of processors without AVX2.
fn kick_drift_plain<const TWICE: bool>(b: Block, dt: f64, g: V3) {
    let half = 0.5 * dt;
    let rows = b.x.iter_mut().zip(b.v.iter_mut()).zip(b.w.iter_mut());
    let rows = rows.zip(b.f.iter_mut()).zip(b.t.iter_mut());
    let props = b.m.iter().zip(b.inv_m).zip(b.inv_i);
    for (((((x, v), w), f), t), ((m, inv_m), inv_i)) in rows.zip(props) {
        let a = inv_m * half;
        let bi = inv_i * half;
        for d in 0..3 {
            if TWICE {
                v[d] += a * f[d];
            }
            v[d] += a * f[d];
            x[d] += dt * v[d];
            if TWICE {
                w[d] += bi * t[d];
            }
            w[d] += bi * t[d];
            f[d] = g[d] * m;
            t[d] = 0.0;
        }
    }
}

/// Four particles at a time: their twelve components in three vectors of four, each
/// particle's factor spread over its components by permutations. A separate multiply and add,
/// as in the plain loop (AVX2 fuses nothing by itself).
///
/// # Safety
/// The processor has AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn kick_drift_avx2<const TWICE: bool>(b: Block, dt: f64, g: V3) {
    use std::arch::x86_64::*;
    let n = b.x.len();
    let full = n / CHUNK * CHUNK;
    let half = _mm256_set1_pd(0.5 * dt);
    let dt4 = _mm256_set1_pd(dt);
    // Gravity over the components of four particles: x y z x | y z x y | z x y z.
    let gq = [
        _mm256_setr_pd(g[0], g[1], g[2], g[0]),
        _mm256_setr_pd(g[1], g[2], g[0], g[1]),
        _mm256_setr_pd(g[2], g[0], g[1], g[2]),
    ];
    // Particle of each component in the three vectors: 0 0 0 1 | 1 1 2 2 | 2 3 3 3.
    #[inline(always)]
    unsafe fn spread(p: __m256d) -> [__m256d; 3] {
        [
            _mm256_permute4x64_pd::<0b01_00_00_00>(p),
            _mm256_permute4x64_pd::<0b10_10_01_01>(p),
            _mm256_permute4x64_pd::<0b11_11_11_10>(p),
        ]
    }
    let (x, v, w) = (
        b.x.as_mut_ptr() as *mut f64,
        b.v.as_mut_ptr() as *mut f64,
        b.w.as_mut_ptr() as *mut f64,
    );
    let (f, t) = (b.f.as_mut_ptr() as *mut f64, b.t.as_mut_ptr() as *mut f64);
    let zero = _mm256_setzero_pd();
    for c in (0..full).step_by(CHUNK) {
        // SAFETY: c + CHUNK <= n for all arrays (same length, checked by the caller), so the
        // twelve components from 3 c lie inside the coordinate arrays.
        let a = spread(_mm256_mul_pd(
            _mm256_loadu_pd(b.inv_m.as_ptr().add(c)),
            half,
        ));
        let bi = spread(_mm256_mul_pd(
            _mm256_loadu_pd(b.inv_i.as_ptr().add(c)),
            half,
        ));
        let m = spread(_mm256_loadu_pd(b.m.as_ptr().add(c)));
        for q in 0..3 {
            let o = 3 * c + 4 * q;
            let fq = _mm256_loadu_pd(f.add(o));
            let mut vq = _mm256_loadu_pd(v.add(o));
            if TWICE {
                vq = _mm256_add_pd(vq, _mm256_mul_pd(a[q], fq));
            }
            vq = _mm256_add_pd(vq, _mm256_mul_pd(a[q], fq));
            _mm256_storeu_pd(v.add(o), vq);
            let xq = _mm256_loadu_pd(x.add(o));
            _mm256_storeu_pd(x.add(o), _mm256_add_pd(xq, _mm256_mul_pd(dt4, vq)));
            let tq = _mm256_loadu_pd(t.add(o));
            let mut wq = _mm256_loadu_pd(w.add(o));
            if TWICE {
                wq = _mm256_add_pd(wq, _mm256_mul_pd(bi[q], tq));
            }
            wq = _mm256_add_pd(wq, _mm256_mul_pd(bi[q], tq));
            _mm256_storeu_pd(w.add(o), wq);
            _mm256_storeu_pd(f.add(o), _mm256_mul_pd(gq[q], m[q]));
            _mm256_storeu_pd(t.add(o), zero);
        }
    }
    kick_drift_plain::<TWICE>(
        Block {
            x: &mut b.x[full..],
            v: &mut b.v[full..],
            w: &mut b.w[full..],
            f: &mut b.f[full..],
            t: &mut b.t[full..],
            m: &b.m[full..],
            inv_m: &b.inv_m[full..],
            inv_i: &b.inv_i[full..],
        },
        dt,
        g,
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    type State = (
        Vec<V3>,
        Vec<V3>,
        Vec<V3>,
        Vec<V3>,
        Vec<V3>,
        Vec<f64>,
        Vec<f64>,
        Vec<f64>,
    );

    fn state(n: usize, seed: u64) -> State {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let mut v3 = |s: f64| -> Vec<V3> {
            (0..n)
                .map(|_| std::array::from_fn(|_| s * rng.random_range(-1.0..1.0)))
                .collect()
        };
        let (x, v, w, f, t) = (v3(0.1), v3(2.0), v3(50.0), v3(1e-2), v3(1e-6));
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed + 1);
        let m: Vec<f64> = (0..n).map(|_| rng.random_range(1e-4..1e-2)).collect();
        let inv_m = m.iter().map(|m| 1.0 / m).collect();
        let inv_i = m.iter().map(|m| 1.0 / (4e-6 * m)).collect();
        (x, v, w, f, t, m, inv_m, inv_i)
    }

    fn block(s: &mut State) -> Block<'_> {
        Block {
            x: &mut s.0,
            v: &mut s.1,
            w: &mut s.2,
            f: &mut s.3,
            t: &mut s.4,
            m: &s.5,
            inv_m: &s.6,
            inv_i: &s.7,
        }
    }

    #[test]
    fn the_vector_kick_is_the_particle_loop_to_the_bit() {
        // On a processor without AVX2 both sides are the plain loop and this checks nothing.
        let (dt, g) = (2e-5, [0.3, -0.2, -9.81]);
        // Lengths around the chunk size, so that the remainder loop is covered too.
        for n in [0, 1, 3, 4, 5, 7, 8, 13] {
            for twice in [false, true] {
                let mut a = state(n, n as u64);
                let mut b = a.clone();
                if twice {
                    kick_drift::<true>(block(&mut a), dt, g);
                    kick_drift_plain::<true>(block(&mut b), dt, g);
                } else {
                    kick_drift::<false>(block(&mut a), dt, g);
                    kick_drift_plain::<false>(block(&mut b), dt, g);
                }
                let bits = |s: &State| -> Vec<u64> {
                    [&s.0, &s.1, &s.2, &s.3, &s.4]
                        .iter()
                        .flat_map(|a| a.iter().flatten().map(|x| x.to_bits()))
                        .collect()
                };
                assert_eq!(bits(&a), bits(&b), "n = {n}, twice = {twice}");
                // The kick did something: a wrong test would also pass on a no-op.
                assert!(n == 0 || a.1 != state(n, n as u64).1);
            }
        }
    }
}
