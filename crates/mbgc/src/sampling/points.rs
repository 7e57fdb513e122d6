//! Point sets in the unit cube, stored row-major in one flat array.

/// A set of points in the unit cube [0, 1]^dim, row-major in one flat `Vec<f64>`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Points {
    dim: usize,
    data: Vec<f64>,
}

impl Points {
    /// An empty set of `dim`-dimensional points.
    pub fn new(dim: usize) -> Self {
        Points {
            dim,
            data: Vec::new(),
        }
    }

    /// An empty set with room for `n` points of dimension `dim`.
    pub fn with_capacity(dim: usize, n: usize) -> Self {
        Points {
            dim,
            data: Vec::with_capacity(dim * n),
        }
    }

    /// Builds from a flat row-major array; panics if its length is not a multiple of `dim`.
    pub fn from_flat(dim: usize, data: Vec<f64>) -> Self {
        assert!(
            dim > 0 && data.len().is_multiple_of(dim),
            "flat data does not fit dim"
        );
        Points { dim, data }
    }

    /// Builds from one `Vec` per point; panics if a row's length differs from `dim`.
    pub fn from_rows(dim: usize, rows: &[Vec<f64>]) -> Self {
        let mut p = Points::with_capacity(dim, rows.len());
        for r in rows {
            p.push(r);
        }
        p
    }

    /// Dimension of every point (the number of free parameters).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Number of points (0 for dimension 0).
    pub fn len(&self) -> usize {
        self.data.len().checked_div(self.dim).unwrap_or(0)
    }

    /// Whether the set holds no points.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Coordinates of point `i`; panics if `i >= len()`.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.dim..(i + 1) * self.dim]
    }

    /// Appends one point; panics if its length differs from `dim`.
    pub fn push(&mut self, row: &[f64]) {
        assert_eq!(row.len(), self.dim, "row has the wrong dimension");
        self.data.extend_from_slice(row);
    }

    /// Iterates over the points as slices of length `dim`.
    pub fn rows(&self) -> impl Iterator<Item = &[f64]> {
        self.data.chunks_exact(self.dim.max(1))
    }

    /// All coordinates, row-major: point `i` occupies `i * dim..(i + 1) * dim`.
    pub fn as_flat(&self) -> &[f64] {
        &self.data
    }

    /// Appends all rows of `other` (same dimension).
    pub fn append(&mut self, other: &Points) {
        assert_eq!(self.dim, other.dim);
        self.data.extend_from_slice(&other.data);
    }
}

/// Squared Euclidean distance between two points of equal dimension; the square root is left to
/// callers that need it, since comparisons need none.
#[inline]
pub fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}
