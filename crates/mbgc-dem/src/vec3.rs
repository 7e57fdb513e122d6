//! Small 3-vector helpers on `[f64; 3]`: plain arrays keep the particle data flat and let the
//! compiler vectorise without a linear-algebra type in the hot loop.

/// A 3-vector (position m, velocity m/s, force N, ...), Cartesian components x, y, z. Cylinder
/// walls and orifice plates are built around the z axis, so scenes take z as up (gravity -z).
pub type V3 = [f64; 3];

/// a + b.
#[inline(always)]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
/// a - b.
#[inline(always)]
pub fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// s a.
#[inline(always)]
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
/// The scalar product a . b.
#[inline(always)]
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
/// The vector product a x b (right-handed).
#[inline(always)]
pub fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// |a|^2, the squared length: compared against squared cut-offs to avoid a square root.
#[inline(always)]
pub fn norm2(a: V3) -> f64 {
    dot(a, a)
}
/// |a|, the Euclidean length.
#[inline(always)]
pub fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
/// a += b.
#[inline(always)]
pub fn add_assign(a: &mut V3, b: V3) {
    a[0] += b[0];
    a[1] += b[1];
    a[2] += b[2];
}
/// a -= b.
#[inline(always)]
pub fn sub_assign(a: &mut V3, b: V3) {
    a[0] -= b[0];
    a[1] -= b[1];
    a[2] -= b[2];
}
