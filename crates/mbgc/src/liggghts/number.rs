//! Numbers as LIGGGHTS reads them.

/// Shortest round-trip form in exponent notation, which LIGGGHTS's number parser accepts.
pub fn num(v: f64) -> String {
    format!("{v:e}")
}
